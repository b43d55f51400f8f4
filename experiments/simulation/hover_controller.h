// A stabilising controller for hover and near-hover flight, fed by the noisy
// measurements (the open-loop hover is unstable): attitude on the swashplate
// (PD), altitude by collective rotor speed (PID), yaw by differential speed
// (PD), and a slow position loop that commands tilt. Signs follow eqs. 31-33:
// delta_cx > 0 gives L > 0, delta_cy > 0 gives M < 0.
#pragma once

#include <map>
#include <string>

#include "core/input_hold.h"
#include "experiments/simulation/scenario.h"

namespace coaxid {

// What the controller sees: measured position (NED), body velocity, Euler
// angles, body rates.
struct Measurement {
  double x, y, z, u, v, w, phi, theta, psi, p, q, r;
};

class HoverController {
 public:
  // trim: the hover inputs; rates: the controller runs at 1/dt_s.
  HoverController(const ControllerGains& gains, const InputVector& trim, double dt_s);
  // The commanded inputs for this tick (before excitation and saturation).
  InputVector Update(const Measurement& y, const Waypoint& target);

 private:
  ControllerGains gains_;
  InputVector trim_;
  double dt_;
  double altitude_integral_ = 0;
};

}  // namespace coaxid
