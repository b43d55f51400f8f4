// Variable-step, variable-order integration of an OdeSystem with SUNDIALS CVODES, optionally
// carrying forward sensitivities
//
//   S = dx/d[x0 | theta],   dS/dt = df/dx * S + [0 | df/dtheta],
//   S(t0) = [I | 0]  (or a caller-supplied S0).
//
// The inputs are held constant between samples (core/input_hold.h), so the
// right-hand side is discontinuous at every sample time. The simulator
// therefore restarts the integrator at every input change (every 5 ms):
// Reset() at t_k, AdvanceTo(t_{k+1}) with a stop time so that no step crosses
// the discontinuity, and so on. Reset() is a cheap CVodeReInit (no
// allocation), and by default the first step of each interval is guessed from
// the previous interval instead of CVODE's initial-step estimator (which costs
// several extra RHS and sensitivity-RHS evaluations per restart).
//
// Hot numeric code: AdvanceTo() and Reset() return false (never throw, never
// abort, never print) and last_error() says why. Bad options are the caller's
// problem: the constructor throws InputError. Size mismatches are bugs: CHECK.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>

#include "dynamics/ode_system.h"

namespace coaxid {

struct IntegratorOptions {
  // kAdams, kBdf: CVODES's multistep methods (variable order). kExplicitRungeKutta: ARKODE's
  // ERKStep with the Dormand-Prince 5(4) pair (dynamics/explicit_runge_kutta.h), a one-step
  // method that loses nothing at the restarts every input change forces; it carries no
  // CVODES sensitivities (integrate the variational equations as states instead,
  // dynamics/variational_system.h) and takes no Newton iteration or max_order.
  enum class Method { kAdams, kBdf, kExplicitRungeKutta };
  Method method = Method::kAdams;
  // Newton iteration with the dense Jacobian from OdeSystem::Jacobians; false = fixed-point
  // (functional) iteration, which needs no Jacobian and suits non-stiff models with Adams.
  bool newton = false;
  double relative_tolerance = 1e-7;  // CVODE rtol (dimensionless).
  double absolute_tolerance = 1e-9;  // CVODE atol, in the units of each state.
  // CVODE mxstep: internal steps allowed in one AdvanceTo() before it fails.
  int max_steps_per_interval = 5000;
  int max_order = 0;  // 0 = CVODE default (12 for Adams, 5 for BDF).
  // Start each interval after a Reset() with a first step learned from the previous interval
  // (a tenth of the order-1 step CVODE chose after its first step there) instead of CVODE's
  // initial-step estimator, which costs extra RHS (and sensitivity RHS) evaluations at every
  // restart. Same accuracy; measured in bench/dynamics/integrator_bench.cc.
  bool initial_step_hint = true;
  // Include the sensitivities in CVODE's local error test (CVodeSetSensErrCon). Off, the step
  // sizes follow the state alone and sensitivities cost far less; their accuracy then rests on
  // the state's steps being fine enough (tests compare both against finite differences).
  bool sensitivity_error_control = true;
  // 0: every state is in CVODE's local error test. k > 0: only the first k states are; the
  // others (e.g. the sensitivity part of a system augmented with its variational equations,
  // dynamics/variational_system.h) ride along on the steps the first k need.
  int error_controlled_states = 0;
  // Use coaxid's compiled-with-optimisation vector kernels instead of the system SUNDIALS
  // library's (dynamics/serial_vector_ops.h). Off only to compare the two.
  bool optimized_vector_ops = true;
  // Read by Simulator, not by Integrator: the state takes one classic RK4 step per hold
  // interval (four right-hand sides) instead of the integrator's adaptive steps, except on an
  // interval that step finds too stiff, which the integrator takes (Simulator::Run).
  bool one_rk4_step_per_hold = false;
  // With one_rk4_step_per_hold: an interval too stiff for that step (its
  // stages read h |lambda| > 2, a mode faster than the holds can follow)
  // fails the run instead of going to the integrator. For fits whose
  // model's physical modes are all slow against the holds: a point with such
  // a mode is outside the model's physical range, refused as a non-finite
  // state is (OutputErrorOptions::DefaultIntegrator).
  bool stiff_holds_fail = false;

  bool IsValid(std::string* why) const;
};

// Which forward sensitivities to carry: columns [initial state (n) if wrt_initial_state] then
// [parameters (p = OdeSystem::NumSensitivityParameters()) if wrt_parameters].
struct SensitivityOptions {
  bool wrt_initial_state = false;
  bool wrt_parameters = false;
};

class Integrator {
 public:
  // `system` must outlive the Integrator. Throws InputError if !options.IsValid() or the system
  // has no states; ComputationError if SUNDIALS cannot allocate its memory.
  Integrator(const OdeSystem& system, const IntegratorOptions& options,
             const SensitivityOptions& sens = {});
  ~Integrator();  // Frees all SUNDIALS memory.
  // Movable (a moved-from Integrator may only be destroyed or assigned to); not copyable. Each
  // Integrator owns its SUNContext and scratch space: use one per thread.
  Integrator(const Integrator&) = delete;
  Integrator& operator=(const Integrator&) = delete;
  Integrator(Integrator&&) noexcept;
  Integrator& operator=(Integrator&&) noexcept;

  // (Re)starts at t0 from x0 (size n). With sensitivities, S0 (n x ns) is the initial
  // sensitivity matrix; nullptr means the natural one ([I | 0] for initial-state columns, 0 for
  // parameter columns). Without sensitivities S0 is ignored. Cheap: CVodeReInit and
  // CVodeSensReInit on memory allocated by the constructor. Call it at every input change.
  // Returns false on a CVODE error (then last_error() says why).
  bool Reset(double t0, const Eigen::VectorXd& x0, const Eigen::MatrixXd* S0 = nullptr);

  // The next interval after a Reset() starts from CVODE's own first-step
  // estimate, as after construction, not from the step learnt on the last
  // interval: a run that calls it first gives the same numbers whatever ran
  // before it.
  void ForgetStepHint();
  // The learnt first-step hint (0: none), and putting one back: a caller that
  // saves it with the state and restores both repeats the same steps exactly
  // (the EKF's checkpointed smoother recomputes stretches of its forward pass).
  double step_hint() const;
  void RestoreStepHint(double hint);

  // Integrates from the current time to t1 > current time without stepping past t1 (stop time
  // t1), and writes the state at t1 to *x and, if S is not null, the sensitivities (n x ns) to
  // *S. The system's held input must not change during the call; change it between calls and
  // then Reset(). Returns false (never throws, never aborts) on any CVODE failure, when
  // OdeSystem::Rhs or ::Jacobians returns false or Rhs returns a non-finite value, when Reset()
  // has not been called since construction or since the last failure, or when t1 is not after
  // the current time; then last_error() says why, and *x, *S are unspecified.
  bool AdvanceTo(double t1, Eigen::VectorXd* x, Eigen::MatrixXd* S = nullptr);

  // Why the last failed call failed; empty after a successful Reset().
  const std::string& last_error() const;
  // ns: number of sensitivity columns (0 if none).
  int num_sensitivities() const;
  // Current time (the t0 of the last Reset() or the t1 of the last successful AdvanceTo()).
  double time() const;

  // Counters summed since construction (CVODE's own counters restart at every ReInit):
  // internal steps, OdeSystem::Rhs calls, OdeSystem::Jacobians calls (Newton and
  // sensitivities), and Reset() calls.
  struct Stats {
    long steps = 0, rhs_evals = 0, jac_evals = 0, restarts = 0;
    Stats& operator+=(const Stats& o) {
      steps += o.steps;
      rhs_evals += o.rhs_evals;
      jac_evals += o.jac_evals;
      restarts += o.restarts;
      return *this;
    }
  };
  Stats stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace coaxid
