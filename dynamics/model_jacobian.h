// Jacobians of the 12-state derivative by automatic differentiation
// (ceres::Jet) of the one templated model (STYLE.md, item 3): the integrator's
// Newton matrix, the CVODES sensitivity equations and the EKF all use these.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/input_hold.h"
#include "dynamics/vehicle_model.h"

namespace coaxid {

// f = xdot(theta, x, input applied at time t of the interval `input`). dfdx:
// 12 x 12. dfdp (optional): 12 x P with column k = df/dtheta[parameter_indices[k]]
// (through the applied input too: a lag's time constant). Returns false if any
// entry is not finite.
bool DerivativeJacobians(const VehicleModel& model, const Eigen::VectorXd& theta,
                         const double* x, const HeldInput& input, double t,
                         const std::vector<int>& parameter_indices, Eigen::MatrixXd* dfdx,
                         Eigen::MatrixXd* dfdp);

// The 15 flight outputs (outputs.h) y at the start of the interval `input`
// (its row's time) and their Jacobians w.r.t. the state (15 x 12) and
// theta[parameter_indices] (15 x P); any output pointer may be null.
bool FlightOutputJacobians(const VehicleModel& model, const Eigen::VectorXd& theta,
                           const double* x, const HeldInput& input,
                           const std::vector<int>& parameter_indices, double* y,
                           Eigen::MatrixXd* dydx, Eigen::MatrixXd* dydp);

// The 15 flight outputs y and their tangents dy (15 x m) = dy/dx x_tangents
// (12 x m) + dy/dtheta[parameter_indices] theta_tangents (P x m): with a
// state's sensitivities S as x_tangents, the outputs' (AutodiffTangents).
bool FlightOutputTangents(const VehicleModel& model, const Eigen::VectorXd& theta,
                          const double* x, const HeldInput& input,
                          const std::vector<int>& parameter_indices,
                          const Eigen::MatrixXd& x_tangents,
                          const Eigen::MatrixXd& theta_tangents, double* y, Eigen::MatrixXd* dy);

// The 10 balance outputs and their Jacobian w.r.t. theta[parameter_indices].
bool BalanceOutputJacobians(const VehicleModel& model, const Eigen::VectorXd& theta,
                            const InputVector& input, const std::vector<int>& parameter_indices,
                            double* y, Eigen::MatrixXd* dydp);

}  // namespace coaxid
