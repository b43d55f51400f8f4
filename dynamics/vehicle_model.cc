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
  ForEachEffectType([&](auto effect, int i) {
    if (effect_offset_[i] >= 0 && decltype(effect)::kChangesFlightMeasurements) {
      changes_measurements_ = true;
    }
  });
}

// The double instantiation is compiled once here; Jet instantiations are made
// where they are used.
template AeroLoads<double> VehicleModel::Loads(const double*, const double*, Setting,
                                               const double*) const;
template void VehicleModel::Derivative(const double*, const double*, const double*,
                                       double*) const;

}  // namespace coaxid
