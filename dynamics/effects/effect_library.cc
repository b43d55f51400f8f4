#include "dynamics/effects/effect_library.h"

namespace coaxid {

const std::vector<EffectInfo>& EffectLibrary() {
  static const std::vector<EffectInfo> library = [] {
    std::vector<EffectInfo> out;
    ForEachEffectType([&](auto effect, int) {
      using E = decltype(effect);
      out.push_back(
          {E::kName, E::kDescription, E::Parameters(), E::kNumOwnStates, E::OwnStateNames()});
    });
    return out;
  }();
  return library;
}

int EffectIndex(const std::string& name) {
  const auto& lib = EffectLibrary();
  for (size_t i = 0; i < lib.size(); ++i) {
    if (lib[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace coaxid
