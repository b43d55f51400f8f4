#include "dynamics/vehicle_ode.h"

#include <cmath>

#include "dynamics/model_jacobian.h"

namespace coaxid {

VehicleOde::VehicleOde(const VehicleModel& model, const Eigen::VectorXd& theta,
                       std::vector<int> sensitivity_parameters)
    : model_(model), theta_(theta), sensitivity_parameters_(std::move(sensitivity_parameters)) {}

bool VehicleOde::Rhs(double t, const double* x, double* xdot) const {
  double u[kNumInputs];
  model_.AppliedInput(theta_.data(), input_, t, u);
  model_.Derivative(theta_.data(), x, u, xdot);
  for (int i = 0; i < model_.NumStates(); ++i) {
    if (!std::isfinite(xdot[i])) return false;
  }
  return true;
}

bool VehicleOde::Jacobians(double t, const double* x, Eigen::MatrixXd* dfdx,
                           Eigen::MatrixXd* dfdp) const {
  return DerivativeJacobians(model_, theta_, x, input_, t, sensitivity_parameters_, dfdx, dfdp);
}

}  // namespace coaxid
