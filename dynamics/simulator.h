// Open-loop simulation of the vehicle over logged zero-order-hold inputs:
// CVODE(S) restarted at every input change, never stepping across one, with
// optional forward sensitivities of the state with respect to the initial
// state and chosen parameters. The output-error segments and the EKF's
// propagation build on this.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/input_hold.h"
#include <memory>

#include "dynamics/integrator.h"
#include "dynamics/rk4.h"
#include "dynamics/rk4_stability.h"
#include "dynamics/variational_system.h"
#include "dynamics/vehicle_ode.h"

namespace coaxid {

struct Trajectory {
  std::vector<double> times;                     // the hold's sample times first..last
  std::vector<Eigen::VectorXd> states;           // x(t_k), 12 each
  std::vector<Eigen::MatrixXd> sensitivities;    // dx(t_k)/d[x0 | params], if asked
  std::vector<HeldInput> inputs;                 // each sample's interval as applied
};

// How sensitivities are computed, all from the autodiff Jacobians of the one
// model:
// - kCvodes: CVODES's forward sensitivity module;
// - kVariationalEquations: the integrator on the state augmented with its
//   variational equations (one vector; sensitivities follow the state's
//   steps, every stage of every step evaluates the Jacobians);
// - kRungeKuttaPerHold: the integrator on the state alone (or the same
//   classic RK4 step, IntegratorOptions::one_rk4_step_per_hold), and one classic
//   Runge-Kutta step per hold interval on the variational equations, with the
//   Jacobians at the interval's two ends and at its midpoint (the state there
//   by cubic Hermite interpolation, O(h^4)): three Jacobians an interval
//   instead of seven or more. Its error, O(h^5) a 5 ms interval, is far below
//   what a Gauss-Newton step or a Cramer-Rao bound can see
//   (tests/dynamics/simulator_test.cc; speed in bench/ident/output_error).
//   Where the model cannot be differentiated at one of those three points
//   (a wild trial point, its midpoint state outside the model's domain), or
//   the interval is too stiff for one RK4 step (h ||A||_inf > 2), that
//   interval falls back to the variational equations, whose integrator
//   takes the state's smaller steps.
enum class SensitivityMethod { kCvodes, kVariationalEquations, kRungeKuttaPerHold };

class Simulator {
 public:
  // sensitivity_parameters: indices into theta of the parameters whose
  // sensitivities are carried when sensitivities.wrt_parameters is set.
  Simulator(const VehicleModel& model, const Eigen::VectorXd& theta,
            const IntegratorOptions& options = {}, const SensitivityOptions& sensitivities = {},
            std::vector<int> sensitivity_parameters = {},
            SensitivityMethod method = SensitivityMethod::kVariationalEquations);

  void SetTheta(const Eigen::VectorXd& theta) { ode_.SetTheta(theta); }

  // Integrates from x0 at inputs.time(first) to inputs.time(last), one hold
  // interval at a time (a lagged input starts where the log's rows before
  // `first` left it, dynamics/held_input.h), and records the state (and sensitivities) at every
  // sample first..last. Returns false with last_error() if CVODE fails or the
  // state stops being finite (blown-up parameters): never throws or aborts.
  // *out is then unspecified. Reusing one Trajectory for many runs of the
  // same length allocates nothing after the first.
  // start: row `first` as applied, when the caller has it (HeldInputPath);
  // null walks the lag from row 0.
  // known_states: the states at samples first..last of a run from the same
  // x0 at the same theta without sensitivities, by a simulator with the same
  // integrator options (the trial point a Jacobian is next asked at). With
  // kRungeKuttaPerHold the state is then not integrated again: only the
  // per-hold sensitivity steps run along it (the integration is a third of
  // a pass with sensitivities, bench/ident/output_error FlightPass). An
  // interval that falls back to the variational equations redoes the run
  // integrating, so the result is bit for bit the run without them.
  bool Run(const InputHold& inputs, int first, int last, const Eigen::VectorXd& x0,
           Trajectory* out, const HeldInput* start = nullptr,
           const std::vector<Eigen::VectorXd>* known_states = nullptr);

  const std::string& last_error() const { return error_; }
  const Integrator& integrator() const { return *integrator_; }
  // Number of sensitivity columns (0 without sensitivities).
  int num_sensitivities() const { return columns_; }
  // kRungeKuttaPerHold: hold intervals whose sensitivities went to the
  // variational equations (the RK4 step failed or was not stable there),
  // since construction.
  long fallback_intervals() const { return fallback_intervals_; }

 private:
  VehicleOde ode_;
  std::unique_ptr<VariationalSystem> variational_;  // set for kVariationalEquations
  std::unique_ptr<Integrator> integrator_;
  // kRungeKuttaPerHold: the variational equations' integrator for the
  // intervals where the per-hold step fails or is too stiff (made at the
  // first).
  IntegratorOptions options_;
  std::unique_ptr<VariationalSystem> fallback_system_;
  std::unique_ptr<Integrator> fallback_;
  // One hold interval [t0, t1] of the state and sensitivities by the
  // variational equations, from (x, S) at t0.
  bool FallBack(double t0, double t1, const Eigen::VectorXd& x0, Eigen::VectorXd* x,
                Eigen::MatrixXd* S);
  SensitivityOptions sensitivity_options_;
  SensitivityMethod method_;
  // kRungeKuttaPerHold: sensitivities of one hold interval [t0, t1] by a
  // classic RK4 step from *S, given the state at both ends.
  bool StepSensitivities(double t0, double t1, const Eigen::VectorXd& x0,
                         const Eigen::VectorXd& x1, Eigen::MatrixXd* S);
  Rk4StabilityTest stability_;  // of the sensitivities' step, on the model's Jacobians
  long fallback_intervals_ = 0;
  struct RungeKuttaScratch {
    Eigen::VectorXd f0, f1, xm;
    Eigen::MatrixXd A0, Am, A1, B0, Bm, B1, K1, K2, K3, K4, Stage;
  } rk_;
  // The state over one hold interval [t0, t1] from *x: one classic RK4 step
  // with options_.one_rk4_step_per_hold (where that step is too stiff or
  // fails, the integrator, or with options_.stiff_holds_fail a failure),
  // else the integrator.
  bool StepState(double t0, double t1, Eigen::VectorXd* x);
  // Why StepState refused its interval (stiff_holds_fail); empty otherwise.
  std::string step_error_;
  // One classic RK4 step of the state; false (x untouched) where the step
  // fails or its stages say h |lambda| > kMaxRungeKuttaStiffness.
  bool RungeKuttaStateStep(double t0, double t1, Eigen::VectorXd* x);
  Rk4Stages state_rk_;
  Eigen::VectorXd state_next_;
  int columns_ = 0;
  std::string error_;
};

}  // namespace coaxid
