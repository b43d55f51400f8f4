// Hover trim: the inputs (omega1, omega2, delta_cx, delta_cy) and attitude
// (phi, theta) that hold the vehicle still (u = v = w = p = q = r = 0) at a
// given position and heading, found by Newton's method on the six
// accelerations of eqs. 40-42 and 47-49 with an autodiff Jacobian.
#pragma once

#include <string>

#include <Eigen/Core>

#include "core/input_hold.h"
#include "dynamics/state.h"
#include "dynamics/vehicle_model.h"

namespace coaxid {

struct HoverTrim {
  Eigen::VectorXd state;  // the equilibrium state (zero velocity and rates; effect states 0)
  InputVector input;    // the trim inputs
  double residual = 0;  // max |acceleration| left at the solution
  int iterations = 0;
};

// Throws ComputationError (with the residual reached) if Newton's method does
// not bring every acceleration below `tolerance`.
HoverTrim TrimHover(const VehicleModel& model, const Eigen::VectorXd& theta, double height_m,
                    double heading_rad = 0.0, double tolerance = 1e-10);

}  // namespace coaxid
