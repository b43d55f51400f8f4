// The interface between a model and the integrator: a right-hand side
// xdot = f(x, theta) for a fixed (held) input, its Jacobians, and the size of
// the sensitivity parameter vector. The vehicle model implements it once
// (dynamics/vehicle_ode.h); tests implement it for systems with closed-form
// solutions.
#pragma once

#include <Eigen/Core>

namespace coaxid {

class OdeSystem {
 public:
  virtual ~OdeSystem() = default;

  // Number of states n.
  virtual int NumStates() const = 0;
  // Number of parameters p whose sensitivities may be asked for (0 if none).
  virtual int NumSensitivityParameters() const = 0;

  // xdot = f(t, x). The input is whatever the system holds at the moment (the
  // integrator calls SetInput-style hooks of the concrete system between
  // intervals; see Integrator). Returns false if f cannot be evaluated (NaN,
  // blown-up parameters); the integrator then reports failure, never crashes.
  virtual bool Rhs(double t, const double* x, double* xdot) const = 0;

  // df/dx (n x n) and df/dp (n x p), column-major Eigen matrices, from
  // automatic differentiation of the same model that Rhs evaluates.
  // dfdp may be nullptr when no parameter sensitivities are needed.
  virtual bool Jacobians(double t, const double* x, Eigen::MatrixXd* dfdx,
                         Eigen::MatrixXd* dfdp) const = 0;
};

}  // namespace coaxid
