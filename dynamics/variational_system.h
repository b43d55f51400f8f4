// An OdeSystem augmented with its variational (sensitivity) equations:
//   z = [x; vec(S)],  xdot = f(x),  Sdot = df/dx S + [0 | df/dp],
// with S = dx/d[x0 | p] stored column by column. Integrated as one vector,
// this gives the same sensitivities as CVODES's forward sensitivity module at
// a fraction of the cost for this small model: CVODES works on one 12-long
// vector per sensitivity, and its per-vector overhead dominates
// (bench/experiments/simulation/flight_bench.cc measures both).
#pragma once

#include <Eigen/Core>

#include "dynamics/ode_system.h"

namespace coaxid {

class VariationalSystem : public OdeSystem {
 public:
  // Columns of S: the n initial-state directions if wrt_initial_state, then
  // the base system's p parameters if wrt_parameters.
  VariationalSystem(const OdeSystem& base, bool wrt_initial_state, bool wrt_parameters);

  int NumStates() const override { return n_ * (1 + columns_); }
  int NumSensitivityParameters() const override { return 0; }
  int NumColumns() const { return columns_; }
  bool Rhs(double t, const double* z, double* zdot) const override;
  // Newton iteration on the augmented system is not offered: use fixed-point
  // iteration (Adams), which suits this non-stiff model.
  bool Jacobians(double, const double*, Eigen::MatrixXd*, Eigen::MatrixXd*) const override {
    return false;
  }

 private:
  const OdeSystem& base_;
  int n_, p_, state_columns_, columns_;
  mutable Eigen::MatrixXd dfdx_, dfdp_;
};

}  // namespace coaxid
