#include "dynamics/model_jacobian.h"

#include <glog/logging.h>

#include "dynamics/autodiff.h"
#include "dynamics/outputs.h"

namespace coaxid {

bool DerivativeJacobians(const VehicleModel& model, const Eigen::VectorXd& theta,
                         const double* x, const HeldInput& input, double t,
                         const std::vector<int>& parameter_indices, Eigen::MatrixXd* dfdx,
                         Eigen::MatrixXd* dfdp) {
  CHECK(dfdx != nullptr);
  return AutodiffJacobian(
      [&](const auto* th, const auto* xx, auto* xdot) {
        using T = std::remove_cv_t<std::remove_pointer_t<decltype(th)>>;
        T u[kNumInputs];
        model.AppliedInput(th, input, t, u);
        model.Derivative(th, xx, u, xdot);
      },
      theta, x, model.NumStates(), model.NumStates(), parameter_indices, nullptr, dfdx, dfdp);
}

bool FlightOutputJacobians(const VehicleModel& model, const Eigen::VectorXd& theta,
                           const double* x, const HeldInput& input,
                           const std::vector<int>& parameter_indices, double* y,
                           Eigen::MatrixXd* dydx, Eigen::MatrixXd* dydp) {
  return AutodiffJacobian(
      [&](const auto* th, const auto* xx, auto* out) {
        FlightOutputsAt(model, th, xx, input, out);
      },
      theta, x, model.NumStates(), kNumFlightChannels, parameter_indices, y, dydx, dydp);
}

bool FlightOutputTangents(const VehicleModel& model, const Eigen::VectorXd& theta,
                          const double* x, const HeldInput& input,
                          const std::vector<int>& parameter_indices,
                          const Eigen::MatrixXd& x_tangents,
                          const Eigen::MatrixXd& theta_tangents, double* y, Eigen::MatrixXd* dy) {
  return AutodiffTangents(
      [&](const auto* th, const auto* xx, auto* out) {
        FlightOutputsAt(model, th, xx, input, out);
      },
      theta, x, model.NumStates(), kNumFlightChannels, parameter_indices, x_tangents,
      theta_tangents, y, dy);
}

bool BalanceOutputJacobians(const VehicleModel& model, const Eigen::VectorXd& theta,
                            const InputVector& input, const std::vector<int>& parameter_indices,
                            double* y, Eigen::MatrixXd* dydp) {
  return AutodiffJacobian(
      [&](const auto* th, const auto* /*no variables*/, auto* out) {
        using T = std::remove_cv_t<std::remove_pointer_t<decltype(th)>>;
        const T u[kNumInputs] = {T(input[0]), T(input[1]), T(input[2]), T(input[3])};
        BalanceOutputs(model, th, u, out);
      },
      theta, nullptr, 0, kNumBalanceChannels, parameter_indices, y, nullptr, dydp);
}

}  // namespace coaxid
