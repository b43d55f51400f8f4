#include "dynamics/vehicle_model.h"

#include <glog/logging.h>

namespace coaxid {

VehicleModel::VehicleModel(InterferenceModel interference,
                           std::shared_ptr<const SigmaTable> table,
                           const std::array<int, kNumEffects>& effect_offset)
    : interference_(interference), table_(std::move(table)), effect_offset_(effect_offset) {
  CHECK(interference_ != InterferenceModel::kTable || (table_ && !table_->empty()))
      << "a tabulated interference model needs a table";
  for (int offset : effect_offset_) any_effect_ = any_effect_ || offset >= 0;
  lag_index_.fill(-1);
  state_offset_.fill(-1);
  ForEachEffectType([&](auto effect, int i) {
    using Effect = decltype(effect);
    if (effect_offset_[i] < 0) return;
    if (Effect::kNumOwnStates > 0) {
      state_offset_[i] = kNumStates + num_effect_states_;
      num_effect_states_ += Effect::kNumOwnStates;
    }
    if (Effect::kChangesFlightMeasurements) changes_measurements_ = true;
    for (int u = 0; u < kNumInputs; ++u) {
      if (Effect::kInputLag[u] < 0) continue;
      CHECK_LT(lag_index_[u], 0) << "two effects lag input " << u;
      lag_index_[u] = effect_offset_[i] + Effect::kInputLag[u];
      lags_inputs_ = true;
    }
  });
}

std::string VehicleModel::NameOfState(int index) const {
  CHECK(index >= 0 && index < NumStates()) << "state " << index << " of " << NumStates();
  if (index < kNumStates) return StateName(index);
  for (int i = 0; i < kNumEffects; ++i) {
    const int first = state_offset_[i];
    const EffectInfo& effect = EffectLibrary()[i];
    if (first >= 0 && index < first + effect.num_own_states && index >= first) {
      return effect.name + "." + effect.own_state_names[index - first];
    }
  }
  LOG(FATAL) << "state " << index << " belongs to no effect";
  return "";
}

// The double instantiation is compiled once here; Jet instantiations are made
// where they are used.
template AeroLoads<double> VehicleModel::Loads(const double*, const double*, Setting,
                                               const double*) const;
template void VehicleModel::Derivative(const double*, const double*, const double*,
                                       double*) const;

}  // namespace coaxid
