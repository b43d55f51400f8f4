// Fixed-step classical Runge-Kutta (RK4) over an OdeSystem: an integrator independent of
// CVODES, used by tests as a reference. Global error O(h^4), h = (t1 - t0) / steps.
//
//   k1 = f(t, x),  k2 = f(t + h/2, x + h/2 k1),  k3 = f(t + h/2, x + h/2 k2),
//   k4 = f(t + h, x + h k3),  x <- x + h/6 (k1 + 2 k2 + 2 k3 + k4).
#pragma once

#include <glog/logging.h>

#include <Eigen/Core>

#include "dynamics/ode_system.h"

namespace coaxid {

// Integrates *x (size n) from t0 to t1 in `steps` equal steps. Returns false if the system's
// Rhs returns false (then *x is unspecified).
inline bool IntegrateRk4(const OdeSystem& system, double t0, double t1, int steps,
                         Eigen::VectorXd* x) {
  CHECK(x != nullptr);
  CHECK_GT(steps, 0);
  const int n = system.NumStates();
  CHECK_EQ(x->size(), n);
  const double h = (t1 - t0) / steps;
  Eigen::VectorXd k1(n), k2(n), k3(n), k4(n), tmp(n);
  for (int i = 0; i < steps; ++i) {
    // t from the step index, not by accumulation, so the last step ends exactly at t1.
    const double t = i + 1 == steps ? t1 - h : t0 + i * h;
    if (!system.Rhs(t, x->data(), k1.data())) return false;
    tmp = *x + 0.5 * h * k1;
    if (!system.Rhs(t + 0.5 * h, tmp.data(), k2.data())) return false;
    tmp = *x + 0.5 * h * k2;
    if (!system.Rhs(t + 0.5 * h, tmp.data(), k3.data())) return false;
    tmp = *x + h * k3;
    if (!system.Rhs(t + h, tmp.data(), k4.data())) return false;
    *x += (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
  return true;
}

}  // namespace coaxid
