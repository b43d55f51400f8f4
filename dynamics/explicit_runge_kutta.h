// The explicit Runge-Kutta back end of Integrator (IntegratorOptions::Method::kExplicitRungeKutta):
// SUNDIALS ARKODE's ERKStep with an embedded 5(4) pair and adaptive steps. Internal to
// dynamics/integrator.cc; use Integrator.
//
// Why a one-step method next to CVODE's multistep ones: the inputs are held constant between
// samples, so the right-hand side is discontinuous every 5 ms and the integrator restarts there.
// A multistep method restarts at order 1 with a small step and climbs back (measured: 7.4 steps
// and 16 RHS calls per 5 ms interval of a closed-loop flight at rtol 1e-7), while a one-step
// method loses nothing at a restart: one Dormand-Prince step usually covers the whole interval
// (bench/experiments/simulation/flight_bench.cc).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>

#include "dynamics/ode_system.h"

namespace coaxid {

struct IntegratorOptions;

class ExplicitRungeKutta {
 public:
  // Throws ComputationError if SUNDIALS cannot allocate its memory. The options must be valid.
  ExplicitRungeKutta(const OdeSystem& system, const IntegratorOptions& options);
  ~ExplicitRungeKutta();
  ExplicitRungeKutta(const ExplicitRungeKutta&) = delete;
  ExplicitRungeKutta& operator=(const ExplicitRungeKutta&) = delete;

  // As Integrator::Reset / AdvanceTo without sensitivities: false and *error on failure.
  bool Reset(double t0, const Eigen::VectorXd& x0, std::string* error);
  // Integrates from the current time t to t1 > t without stepping past t1. The first step after
  // a Reset() is `first_step` (0: ARKODE's estimate) capped at t1 - t. On success,
  // *next_first_step is the step the error controller proposes next (a good first step for the
  // next interval).
  bool AdvanceTo(double t, double t1, double first_step, double* x, double* next_first_step,
                 std::string* error);

  long steps() const;      // Accepted steps since construction.
  long rhs_evals() const;  // OdeSystem::Rhs calls since construction.

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace coaxid
