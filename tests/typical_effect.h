// A library effect at its typical strength (EffectParameterSpec::typical: a
// clearly visible but realistic value), as a scenario's truth effect.
#pragma once

#include <map>
#include <string>
#include <utility>

#include "dynamics/effects/effect_library.h"
#include "experiments/simulation/scenario.h"

namespace coaxid {

inline std::pair<std::string, std::map<std::string, ParameterOverride>> TypicalEffect(
    const std::string& name) {
  std::map<std::string, ParameterOverride> values;
  for (const EffectParameterSpec& p : EffectLibrary()[EffectIndex(name)].parameters) {
    values[p.name].value = p.typical;
  }
  return {name, values};
}

}  // namespace coaxid
