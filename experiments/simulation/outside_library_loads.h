// Two loads no library effect describes, for simulated truths only (scenario
// key truth.outside_library): the discover confusion study (issue 13) checks
// that the loop reports their channels as unexplained and adds nothing.
//   yaw_from_swashplate [N m/rad]: N += k delta_cx, a yaw moment that follows
//     the lateral swashplate angle (e.g. a lower-rotor torque asymmetry);
//   thrust_from_climb_rate [s/m]: the rotor thrust falls with the climb rate
//     c = -w as T (1 - k c) (inflow change), i.e. Z += k w Z_T.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "dynamics/truth_only_loads.h"

namespace coaxid {

struct OutsideLibraryStrengths {
  double yaw_from_swashplate = 0;     // N m per rad
  double thrust_from_climb_rate = 0;  // per (m/s) of climb
  bool Any() const { return yaw_from_swashplate != 0 || thrust_from_climb_rate != 0; }
};

// The names accepted under truth.outside_library.
const std::vector<std::string>& OutsideLibraryNames();

// From the scenario's map; throws InputError naming `where` on an unknown name.
OutsideLibraryStrengths ParseOutsideLibrary(const std::map<std::string, double>& values,
                                            const std::string& where);

class OutsideLibraryLoads : public TruthOnlyLoads {
 public:
  explicit OutsideLibraryLoads(const OutsideLibraryStrengths& s) : s_(s) {}
  void Add(const EffectContext<double>& c, AeroLoads<double>* loads) const override;

 private:
  OutsideLibraryStrengths s_;
};

}  // namespace coaxid
