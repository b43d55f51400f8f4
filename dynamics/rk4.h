// Fixed-step classical Runge-Kutta (RK4) over an OdeSystem: an integrator independent of
// CVODES, used by tests as a reference, and the step the output-error fits' simulator takes
// a hold (Simulator, IntegratorOptions::one_rk4_step_per_hold). Global error O(h^4), h = (t1 - t0) / steps.
//
//   k1 = f(t, x),  k2 = f(t + h/2, x + h/2 k1),  k3 = f(t + h/2, x + h/2 k2),
//   k4 = f(t + h, x + h k3),  x <- x + h/6 (k1 + 2 k2 + 2 k3 + k4).
#pragma once

#include <glog/logging.h>

#include <Eigen/Core>

#include "dynamics/ode_system.h"

namespace coaxid {

// One step of h from (t, x) into *x_next, keeping the stages in *stages (the simulator reads
// its stiffness estimate from them). Returns false if the system's Rhs returns false.
struct Rk4Stages {
  Eigen::VectorXd k1, k2, k3, k4, tmp;
};
inline bool Rk4Step(const OdeSystem& system, double t, double h, const Eigen::VectorXd& x,
                    Rk4Stages* s, Eigen::VectorXd* x_next) {
  const int n = static_cast<int>(x.size());
  for (Eigen::VectorXd* v : {&s->k1, &s->k2, &s->k3, &s->k4, &s->tmp}) v->resize(n);
  if (!system.Rhs(t, x.data(), s->k1.data())) return false;
  s->tmp = x + 0.5 * h * s->k1;
  if (!system.Rhs(t + 0.5 * h, s->tmp.data(), s->k2.data())) return false;
  s->tmp = x + 0.5 * h * s->k2;
  if (!system.Rhs(t + 0.5 * h, s->tmp.data(), s->k3.data())) return false;
  s->tmp = x + h * s->k3;
  if (!system.Rhs(t + h, s->tmp.data(), s->k4.data())) return false;
  *x_next = x + (h / 6.0) * (s->k1 + 2.0 * s->k2 + 2.0 * s->k3 + s->k4);
  return true;
}

// Integrates *x (size n) from t0 to t1 in `steps` equal steps. Returns false if the system's
// Rhs returns false (then *x is unspecified).
inline bool IntegrateRk4(const OdeSystem& system, double t0, double t1, int steps,
                         Eigen::VectorXd* x) {
  CHECK(x != nullptr);
  CHECK_GT(steps, 0);
  CHECK_EQ(x->size(), system.NumStates());
  const double h = (t1 - t0) / steps;
  Rk4Stages stages;
  Eigen::VectorXd next;
  for (int i = 0; i < steps; ++i) {
    // t from the step index, not by accumulation, so the last step ends exactly at t1.
    const double t = i + 1 == steps ? t1 - h : t0 + i * h;
    if (!Rk4Step(system, t, h, *x, &stages, &next)) return false;
    x->swap(next);
  }
  return true;
}

}  // namespace coaxid
