// The vehicle model as an OdeSystem for the integrator: the state
// derivative (eqs. 34-49, and any effect's own states) over one hold interval set by SetInput (the logged
// row held, model.md; a lagged actuator's exact exponential inside it,
// dynamics/held_input.h), and its Jacobians by automatic differentiation.
#pragma once

#include <vector>

#include "core/input_hold.h"
#include "dynamics/held_input.h"
#include "dynamics/ode_system.h"
#include "dynamics/vehicle_model.h"

namespace coaxid {

class VehicleOde : public OdeSystem {
 public:
  // theta: the full parameter vector. sensitivity_parameters: indices into
  // theta of the parameters whose sensitivities the integrator may carry.
  VehicleOde(const VehicleModel& model, const Eigen::VectorXd& theta,
             std::vector<int> sensitivity_parameters = {});

  void SetInput(const HeldInput& input) { input_ = input; }
  const HeldInput& input() const { return input_; }
  const VehicleModel& model() const { return model_; }
  void SetTheta(const Eigen::VectorXd& theta) { theta_ = theta; }
  const Eigen::VectorXd& theta() const { return theta_; }

  int NumStates() const override { return model_.NumStates(); }
  int NumSensitivityParameters() const override {
    return static_cast<int>(sensitivity_parameters_.size());
  }
  bool Rhs(double t, const double* x, double* xdot) const override;
  bool Jacobians(double t, const double* x, Eigen::MatrixXd* dfdx,
                 Eigen::MatrixXd* dfdp) const override;

 private:
  const VehicleModel& model_;
  Eigen::VectorXd theta_;
  std::vector<int> sensitivity_parameters_;
  HeldInput input_;
};

}  // namespace coaxid
