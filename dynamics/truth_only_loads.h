// Loads a simulated truth may hold that no model being identified has: the
// "effects outside the library" of the discover confusion study (issue 13),
// which must come out as "unexplained", never as a library effect. Only the
// double-valued model (the simulator, the accelerometer output) applies them;
// estimators never set them, so their Jet models cannot see them.
#pragma once

#include "dynamics/effects/effect.h"

namespace coaxid {

class TruthOnlyLoads {
 public:
  virtual ~TruthOnlyLoads() = default;
  // Adds to *loads (body axes, gravity excluded) at the model's operating point.
  virtual void Add(const EffectContext<double>& context, AeroLoads<double>* loads) const = 0;
};

}  // namespace coaxid
