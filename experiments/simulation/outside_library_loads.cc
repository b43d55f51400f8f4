#include "experiments/simulation/outside_library_loads.h"

#include "core/errors.h"

namespace coaxid {

const std::vector<std::string>& OutsideLibraryNames() {
  static const std::vector<std::string> names = {"yaw_from_swashplate", "thrust_from_climb_rate"};
  return names;
}

OutsideLibraryStrengths ParseOutsideLibrary(const std::map<std::string, double>& values,
                                            const std::string& where) {
  OutsideLibraryStrengths s;
  for (const auto& [name, value] : values) {
    if (name == "yaw_from_swashplate") {
      s.yaw_from_swashplate = value;
    } else if (name == "thrust_from_climb_rate") {
      s.thrust_from_climb_rate = value;
    } else {
      throw InputError(where + ": unknown outside-library load '" + name +
                       "' (expected yaw_from_swashplate or thrust_from_climb_rate)");
    }
  }
  return s;
}

void OutsideLibraryLoads::Add(const EffectContext<double>& c, AeroLoads<double>* loads) const {
  loads->moment_B[2] += s_.yaw_from_swashplate * c.delta_cx;
  // Z_T < 0 (up); climbing (w < 0) lowers the thrust magnitude for k > 0.
  loads->force_B[2] += s_.thrust_from_climb_rate * c.v_B[2] * c.rotor_z;
}

}  // namespace coaxid
