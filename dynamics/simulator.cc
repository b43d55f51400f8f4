#include "dynamics/simulator.h"

#include <algorithm>

#include <glog/logging.h>

namespace coaxid {
namespace {

// The integrator's options for a state of n augmented with its variational
// equations.
IntegratorOptions AugmentedOptions(const IntegratorOptions& options, int n) {
  IntegratorOptions augmented = options;
  augmented.newton = false;  // fixed-point iteration on the augmented system
  // Step sizes follow the state, as with CVODES and sensitivity_error_control off.
  if (!options.sensitivity_error_control) augmented.error_controlled_states = n;
  return augmented;
}

// h |lambda| above which an interval leaves the RK4 step (the state's by its
// stages, the sensitivities' by rk4_stability.h): below the step's real-axis
// stability limit 2.79, where it still damps a mode of h lambda = -2 to 1/3
// a step (exactly: e^-2 = 0.14).
constexpr double kMaxRungeKuttaStiffness = 2.0;

}  // namespace

Simulator::Simulator(const VehicleModel& model, const Eigen::VectorXd& theta,
                     const IntegratorOptions& options, const SensitivityOptions& sensitivities,
                     std::vector<int> sensitivity_parameters, SensitivityMethod method)
    : ode_(model, theta, std::move(sensitivity_parameters)),
      options_(options),
      sensitivity_options_(sensitivities),
      method_(method),
      stability_(kMaxRungeKuttaStiffness) {
  const bool wanted = sensitivities.wrt_initial_state || sensitivities.wrt_parameters;
  if (wanted && method == SensitivityMethod::kRungeKuttaPerHold) {
    const int n = ode_.NumStates(), p = sensitivities.wrt_parameters
                                            ? ode_.NumSensitivityParameters() : 0;
    columns_ = (sensitivities.wrt_initial_state ? n : 0) + p;
    integrator_ = std::make_unique<Integrator>(ode_, options);
    rk_.f0.resize(n);
    rk_.f1.resize(n);
    rk_.xm.resize(n);
    for (Eigen::MatrixXd* A : {&rk_.A0, &rk_.Am, &rk_.A1}) A->setZero(n, n);
    for (Eigen::MatrixXd* B : {&rk_.B0, &rk_.Bm, &rk_.B1}) B->setZero(n, p);
    for (Eigen::MatrixXd* K : {&rk_.K1, &rk_.K2, &rk_.K3, &rk_.K4, &rk_.Stage}) {
      K->setZero(n, columns_);
    }
  } else if (wanted && method == SensitivityMethod::kVariationalEquations) {
    variational_ = std::make_unique<VariationalSystem>(ode_, sensitivities.wrt_initial_state,
                                                       sensitivities.wrt_parameters);
    columns_ = variational_->NumColumns();
    integrator_ =
        std::make_unique<Integrator>(*variational_, AugmentedOptions(options, ode_.NumStates()));
  } else {
    integrator_ = std::make_unique<Integrator>(ode_, options, sensitivities);
    columns_ = integrator_->num_sensitivities();
  }
}

bool Simulator::Run(const InputHold& inputs, int first, int last, const Eigen::VectorXd& x0,
                    Trajectory* out, const HeldInput* start,
                    const std::vector<Eigen::VectorXd>* known_states) {
  CHECK(first >= 0 && first <= last && last < inputs.size());
  const int n = ode_.NumStates();
  CHECK_EQ(x0.size(), n);
  // Sized once and written in place: a trajectory reused for the next run
  // (output-error segments keep theirs) allocates nothing.
  const int samples = last - first + 1;
  out->times.resize(samples);
  out->states.resize(samples);
  out->inputs.resize(samples);
  const InputVector lag = ode_.model().InputLags(ode_.theta().data());
  out->inputs[0] = start ? *start : HeldInputAt(inputs, first, lag);
  out->times[0] = inputs.time(first);
  out->states[0] = x0;
  const bool with_sensitivities = columns_ > 0;
  const bool replay = known_states != nullptr && with_sensitivities &&
                      method_ == SensitivityMethod::kRungeKuttaPerHold;
  if (replay) CHECK_EQ(static_cast<int>(known_states->size()), last - first + 1);
  out->sensitivities.resize(with_sensitivities ? samples : 0);
  // The natural initial sensitivities: [I | 0] (initial-state columns come
  // first when carried, SensitivityOptions).
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(n, columns_);
  if (sensitivity_options_.wrt_initial_state && columns_ >= n) S.leftCols(n).setIdentity();
  if (with_sensitivities) out->sensitivities[0] = S;

  // A run is a function of its arguments alone (the same point simulated
  // twice gives the same numbers).
  integrator_->ForgetStepHint();
  stability_.Reset();
  Eigen::VectorXd x = x0, x_start(n);
  Eigen::VectorXd z(variational_ ? variational_->NumStates() : 0);
  for (int k = first; k < last; ++k) {
    const HeldInput& held = out->inputs[k - first];
    ode_.SetInput(held);
    // Restart at every input change: the right-hand side jumps there.
    bool ok;
    if (method_ == SensitivityMethod::kRungeKuttaPerHold && with_sensitivities) {
      x_start = x;
      if (replay) {
        x = (*known_states)[k + 1 - first];
        ok = true;
      } else {
        ok = StepState(inputs.time(k), inputs.time(k + 1), &x);
      }
      if (ok && x.allFinite() &&
          !StepSensitivities(inputs.time(k), inputs.time(k + 1), x_start, x, &S)) {
        // The fallback's state replaces the integrator's from here on, and
        // the integrator's next step hint is the one it would have had: the
        // run is redone integrating, as without known states.
        if (replay) return Run(inputs, first, last, x0, out, start);
        if (!FallBack(inputs.time(k), inputs.time(k + 1), x_start, &x, &S)) {
          error_ = "sensitivities failed between t = " + std::to_string(inputs.time(k)) +
                   " and " + std::to_string(inputs.time(k + 1)) + " s: " + fallback_->last_error();
          return false;
        }
      }
    } else if (variational_) {
      z.head(n) = x;
      z.tail(z.size() - n) = Eigen::Map<const Eigen::VectorXd>(S.data(), S.size());
      ok = integrator_->Reset(inputs.time(k), z) && integrator_->AdvanceTo(inputs.time(k + 1), &z);
      if (ok) {
        x = z.head(n);
        S = Eigen::Map<const Eigen::MatrixXd>(z.data() + n, n, columns_);
      }
    } else if (!with_sensitivities) {
      ok = StepState(inputs.time(k), inputs.time(k + 1), &x);
    } else {
      ok = integrator_->Reset(inputs.time(k), x, &S) &&
           integrator_->AdvanceTo(inputs.time(k + 1), &x, &S);
    }
    if (!ok) {
      error_ = "integration failed between t = " + std::to_string(inputs.time(k)) + " and " +
               std::to_string(inputs.time(k + 1)) +
               " s: " + (step_error_.empty() ? integrator_->last_error() : step_error_);
      return false;
    }
    if (!x.allFinite()) {
      error_ = "state not finite at t = " + std::to_string(inputs.time(k + 1)) + " s";
      return false;
    }
    const int i = k + 1 - first;
    out->inputs[i] = NextHeldInput(held, lag, inputs.input(k + 1), inputs.time(k + 1));
    if (with_sensitivities) out->sensitivities[i] = S;
    out->times[i] = inputs.time(k + 1);
    out->states[i] = x;
  }
  return true;
}

bool Simulator::StepState(double t0, double t1, Eigen::VectorXd* x) {
  step_error_.clear();
  if (options_.one_rk4_step_per_hold) {
    if (RungeKuttaStateStep(t0, t1, x)) return true;
    if (options_.stiff_holds_fail) {
      // kMaxRungeKuttaStiffness, 2.
      step_error_ =
          "one RK4 step over the hold failed or found a mode faster than the holds can follow "
          "(h |lambda| > 2), outside the physical range a fit accepts";
      return false;
    }
  }
  return integrator_->Reset(t0, *x) && integrator_->AdvanceTo(t1, x);
}

bool Simulator::RungeKuttaStateStep(double t0, double t1, Eigen::VectorXd* x) {
  Rk4Stages& w = state_rk_;
  if (!Rk4Step(ode_, t0, t1 - t0, *x, &w, &state_next_) || !state_next_.allFinite()) return false;
  // Stiffness from the stages (Hairer's DOPRI5 test): the second and third
  // sit (h / 2) (k2 - k1) apart, so 2 |k3 - k2| / |k2 - k1| estimates
  // h |lambda| along that direction. Beyond the RK4 sensitivity step's own
  // limit the integrator takes the interval. A stiff mode with a small share
  // of the stages' spread (a bar tilt decayed to its equilibrium) passes
  // until the step has grown it into view: the state stays bounded, off by
  // about 1e-4 (simulator_test, a bar 50 times faster than its bounds
  // allow). Read per state instead, the test tripped on 17 % of the holds
  // (a rate crossing zero) and cost more than it saved.
  const double spread = (w.k2 - w.k1).norm();
  if (spread > 0 && 2 * (w.k3 - w.k2).norm() > kMaxRungeKuttaStiffness * spread) return false;
  x->swap(state_next_);
  return true;
}

bool Simulator::FallBack(double t0, double t1, const Eigen::VectorXd& x0, Eigen::VectorXd* x,
                         Eigen::MatrixXd* S) {
  const int n = ode_.NumStates();
  ++fallback_intervals_;
  if (!fallback_) {
    fallback_system_ = std::make_unique<VariationalSystem>(
        ode_, sensitivity_options_.wrt_initial_state, sensitivity_options_.wrt_parameters);
    fallback_ = std::make_unique<Integrator>(*fallback_system_, AugmentedOptions(options_, n));
  }
  // S still holds the interval's start: StepSensitivities writes it only on success.
  Eigen::VectorXd z(n * (1 + columns_));
  z.head(n) = x0;
  z.tail(n * columns_) = Eigen::Map<const Eigen::VectorXd>(S->data(), S->size());
  fallback_->ForgetStepHint();
  if (!fallback_->Reset(t0, z) || !fallback_->AdvanceTo(t1, &z)) return false;
  *x = z.head(n);
  *S = Eigen::Map<const Eigen::MatrixXd>(z.data() + n, n, columns_);
  return S->allFinite();
}

bool Simulator::StepSensitivities(double t0, double t1, const Eigen::VectorXd& x0,
                                  const Eigen::VectorXd& x1, Eigen::MatrixXd* S) {
  RungeKuttaScratch& w = rk_;
  const int p = static_cast<int>(w.B0.cols());
  const double h = t1 - t0, tm = t0 + h / 2;
  Eigen::MatrixXd* no_p = nullptr;
  // The state at the midpoint: cubic Hermite from both ends' values and slopes.
  if (!ode_.Rhs(t0, x0.data(), w.f0.data()) || !ode_.Rhs(t1, x1.data(), w.f1.data())) {
    return false;
  }
  w.xm = 0.5 * (x0 + x1) + (h / 8) * (w.f0 - w.f1);
  if (!ode_.Jacobians(t0, x0.data(), &w.A0, p > 0 ? &w.B0 : no_p) ||
      !ode_.Jacobians(tm, w.xm.data(), &w.Am, p > 0 ? &w.Bm : no_p) ||
      !ode_.Jacobians(t1, x1.data(), &w.A1, p > 0 ? &w.B1 : no_p)) {
    return false;
  }
  // One RK4 step is stable only while h |lambda| stays inside its stability
  // region (dynamics/rk4_stability.h). A stiffer interval (a wild trial
  // point: measured h ||A|| up to 1000 at a refit restarting declared
  // parameters, with sensitivities grown to 1e8 along the segment) goes to
  // the variational equations, whose steps follow the state's.
  if (!stability_.Stable(h, w.A0) || !stability_.Stable(h, w.Am) ||
      !stability_.Stable(h, w.A1)) {
    return false;
  }
  // dS/dt = A S + [0 | B].
  auto slope = [p](const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& s,
                   Eigen::MatrixXd* k) {
    k->noalias() = A * s;
    if (p > 0) k->rightCols(p) += B;
  };
  slope(w.A0, w.B0, *S, &w.K1);
  w.Stage = *S + (h / 2) * w.K1;
  slope(w.Am, w.Bm, w.Stage, &w.K2);
  w.Stage = *S + (h / 2) * w.K2;
  slope(w.Am, w.Bm, w.Stage, &w.K3);
  w.Stage = *S + h * w.K3;
  slope(w.A1, w.B1, w.Stage, &w.K4);
  w.Stage = *S + (h / 6) * (w.K1 + 2 * w.K2 + 2 * w.K3 + w.K4);
  if (!w.Stage.allFinite()) return false;
  S->swap(w.Stage);
  return true;
}

}  // namespace coaxid
