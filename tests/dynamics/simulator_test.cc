// The simulator on the real vehicle model: CVODE against an independent
// fixed-step RK4, and CVODES sensitivities against finite differences of
// whole simulations.
#include "dynamics/simulator.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "dynamics/rk4.h"
#include "dynamics/rk4_stability.h"
#include "dynamics/trim.h"
#include "dynamics/vehicle.h"
#include "experiments/simulation/simulate_experiment.h"

namespace coaxid {
namespace {

// A logged closed-loop flight with every effect on, so the replay exercises
// the whole model (stabilizer_bar's two states included: 14 states); its inputs are replayed open loop for 1 s (the open-loop
// hover diverges slowly enough over 1 s to stay near hover).
struct Fixture {
  Vehicle vehicle;
  InputHold inputs;
  Eigen::VectorXd x0;
};

Fixture MakeFixture() {
  Fixture f;
  VehicleConfig config = LoadVehicleConfig(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
  for (const EffectInfo& info : EffectLibrary()) {
    std::map<std::string, ParameterOverride> overrides;
    for (const auto& p : info.parameters) overrides[p.name].value = p.typical;
    config.effects.emplace_back(info.name, overrides);
  }
  f.vehicle = MakeVehicle(config);
  FlightScenario scenario;
  scenario.duration_s = 3;
  scenario.excitation.start_s = 0.5;
  const Log log = SimulateFlight(f.vehicle, scenario, 7);
  f.inputs = InputHold::FromLog(log);
  f.x0 = TrimHover(f.vehicle.model, f.vehicle.parameters.Values(), 1.5).state;
  f.x0[kU] = 0.1;  // some motion so every term of the model is active
  f.x0[kQ] = 0.05;
  // The stabilizer bar's tilt (its two states follow the 12), off the shaft.
  const int bar = f.vehicle.model.EffectStateOffset(EffectIndex("stabilizer_bar"));
  f.x0[bar] = 0.01;
  f.x0[bar + 1] = -0.02;
  return f;
}

// The vehicle with the applied inputs as four more states,
// d(u_a)/dt = (u_logged - u_a) / T for each lagged input (effects.md:
// servo_lag, motor_lag): the lags integrated as an ODE, independent of the
// exponential the simulator evaluates (dynamics/held_input.h).
class LagAsStates : public OdeSystem {
 public:
  explicit LagAsStates(const Vehicle& v)
      : v_(v), n_(v.model.NumStates()), theta_(v.parameters.Values()),
        lag_(v.model.InputLags(theta_.data())) {}
  void SetLogged(const InputVector& u) { logged_ = u; }
  int NumStates() const override { return n_ + kNumInputs; }
  int NumSensitivityParameters() const override { return 0; }
  bool Rhs(double /*t*/, const double* z, double* zdot) const override {
    v_.model.Derivative(theta_.data(), z, z + n_, zdot);
    for (int i = 0; i < kNumInputs; ++i) {
      zdot[n_ + i] = lag_[i] > 0 ? (logged_[i] - z[n_ + i]) / lag_[i] : 0.0;
    }
    return true;
  }
  bool Jacobians(double, const double*, Eigen::MatrixXd*, Eigen::MatrixXd*) const override {
    return false;
  }
  // An unlagged input is the logged one.
  void Unlagged(Eigen::VectorXd* z) const {
    for (int i = 0; i < kNumInputs; ++i) {
      if (!(lag_[i] > 0)) (*z)[n_ + i] = logged_[i];
    }
  }

 private:
  const Vehicle& v_;
  int n_;  // the vehicle's states, effect states included
  Eigen::VectorXd theta_;
  InputVector lag_;
  InputVector logged_{};
};

TEST(Simulator, AgreesWithIndependentRk4) {
  const Fixture f = MakeFixture();
  IntegratorOptions tight;
  tight.relative_tolerance = 1e-10;
  tight.absolute_tolerance = 1e-12;
  Simulator simulator(f.vehicle.model, f.vehicle.parameters.Values(), tight);
  const int last = 400;  // 2 s at 200 Hz
  Trajectory trajectory;
  ASSERT_TRUE(simulator.Run(f.inputs, 100, last, f.x0, &trajectory)) << simulator.last_error();

  // Every library effect is on, the actuator lags among them: the applied
  // inputs start at the first row's logged ones and lag through rows 0-99.
  ASSERT_TRUE(f.vehicle.model.LagsInputs());
  const int n = f.vehicle.model.NumStates();
  ASSERT_EQ(n, kNumStates + 2);  // the stabilizer bar's tilt
  LagAsStates ode(f.vehicle);
  const InputVector lag = f.vehicle.model.InputLags(f.vehicle.parameters.Values().data());
  Eigen::VectorXd z(n + kNumInputs);
  z.head(n) = f.x0;
  for (int i = 0; i < kNumInputs; ++i) z[n + i] = f.inputs.input(0)[i];
  for (int k = 0; k < last; ++k) {
    ode.SetLogged(f.inputs.input(k));
    ode.Unlagged(&z);
    // 50 RK4 steps of 0.1 ms per 5 ms hold: error ~ h^4 * |f''''| is far
    // below 1e-9 for this smooth model (and for the lags, h / T <= 1/400).
    const Eigen::VectorXd before = z;
    ASSERT_TRUE(IntegrateRk4(ode, f.inputs.time(k), f.inputs.time(k + 1), 50, &z));
    if (k < 100) {  // before the replay starts only the lags run
      z.head(n) = before.head(n);
      continue;
    }
    const Eigen::VectorXd& cvode = trajectory.states[k + 1 - 100];
    for (int i = 0; i < n; ++i) {
      // Both integrators are accurate to ~1e-9 here; 1e-7 leaves margin for
      // the error growth of the unstable hover over 2 s.
      ASSERT_NEAR(cvode[i], z[i], 1e-7 * (1 + std::fabs(z[i])))
          << "state " << (i < kNumStates ? StateName(i) : "bar") << " at t = "
          << f.inputs.time(k + 1);
    }
    // The applied inputs the simulator carried to the next row (rotor
    // speeds ~300 rad/s: relative).
    for (int i = 0; i < kNumInputs; ++i) {
      const double expected = lag[i] > 0 ? z[n + i] : f.inputs.input(k + 1)[i];
      ASSERT_NEAR(trajectory.inputs[k + 1 - 100].start[i], expected,
                  1e-12 * (1 + std::fabs(expected)))
          << "applied input " << i << " at t = " << f.inputs.time(k + 1);
    }
  }
}

class SimulatorSensitivities : public ::testing::TestWithParam<SensitivityMethod> {};

TEST_P(SimulatorSensitivities, EqualFiniteDifferencesOfWholeSimulations) {
  const Fixture f = MakeFixture();
  const Eigen::VectorXd theta = f.vehicle.parameters.Values();
  // Every parameter of the vehicle (known ones too: the equations allow it).
  std::vector<int> params;
  for (int i = 0; i < theta.size(); ++i) params.push_back(i);
  IntegratorOptions options;
  options.relative_tolerance = 1e-10;
  options.absolute_tolerance = 1e-12;
  // Sensitivities follow the state's steps (not in the error test): the
  // configuration the estimators use.
  options.sensitivity_error_control = false;
  Simulator simulator(f.vehicle.model, theta, options, {true, true}, params, GetParam());
  const int first = 100, last = 300;  // 1 s
  Trajectory trajectory;
  ASSERT_TRUE(simulator.Run(f.inputs, first, last, f.x0, &trajectory)) << simulator.last_error();
  const Eigen::MatrixXd& S = trajectory.sensitivities.back();
  const int n = f.vehicle.model.NumStates();  // the bar's two states included
  ASSERT_EQ(S.cols(), n + static_cast<int>(params.size()));

  Simulator plain(f.vehicle.model, theta, options);
  auto final_state = [&](const Eigen::VectorXd& th, const Eigen::VectorXd& x0) {
    plain.SetTheta(th);
    Trajectory t;
    EXPECT_TRUE(plain.Run(f.inputs, first, last, x0, &t));
    return t.states.back();
  };
  const int columns = S.cols();
  for (int c = 0; c < columns; ++c) {
    Eigen::VectorXd th = theta, x0 = f.x0;
    double* target = c < n ? &x0[c] : &th[params[c - n]];
    // Central differences with a step of 1e-5 of the coordinate's scale (the
    // parameter's own scale, 1 for states): truncation error ~1e-10 relative,
    // round-off ~ tol/step ~ 1e-7 relative.
    const double h =
        1e-5 * (c < n ? 1.0 : f.vehicle.parameters[params[c - n]].scale);
    const double saved = *target;
    *target = saved + h;
    const Eigen::VectorXd plus = final_state(th, x0);
    *target = saved - h;
    const Eigen::VectorXd minus = final_state(th, x0);
    const Eigen::VectorXd fd = (plus - minus) / (2 * h);
    const double scale = std::max(fd.norm(), S.col(c).norm());
    if (scale < 1e-12) continue;  // this direction does not move the state at all
    if (S.col(c).isZero(0)) {
      // A parameter the dynamics do not read (a measurement effect's bias):
      // the two runs differ only in the last bits of their states (~eps |x|
      // each), so the difference quotient is round-off, ~eps |x| / h.
      const double x_size = std::max(plus.cwiseAbs().maxCoeff(), 1.0);
      EXPECT_LT(fd.norm(), 1e3 * std::numeric_limits<double>::epsilon() * x_size / h)
          << "column " << c << " " << f.vehicle.parameters[params[c - n]].name
          << ": CVODES says the state does not depend on it\nFD:   " << fd.transpose();
      continue;
    }
    EXPECT_LT((fd - S.col(c)).norm(), 1e-4 * scale)
        << "column " << c
        << (c < n ? std::string(" x0.") + (c < kNumStates ? StateName(c) : "bar")
                  : " " + f.vehicle.parameters[params[c - n]].name)
        << "\nFD:   " << fd.transpose() << "\nCVODES: " << S.col(c).transpose();
  }
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, SimulatorSensitivities,
                         ::testing::Values(SensitivityMethod::kCvodes,
                                           SensitivityMethod::kVariationalEquations,
                                           SensitivityMethod::kRungeKuttaPerHold));

// One RK4 step per hold interval against the variational equations on the
// integrator's own steps at a tight tolerance (the reference): the per-hold
// step's truncation error, O(h^5) with h = 5 ms, is what separates them.
// Measured: 2.9e-7 of the column's largest size over the 1 s at worst (every
// column, the bar's states included); 1e-5 leaves a margin of 35 and is
// still ten times tighter than the finite-difference check above.
// The per-hold RK4 sensitivities against the variational equations at a
// tight tolerance, over rows 100..300 (1 s) at `theta`: the largest error of
// a column relative to its largest size over the second (a column starts at
// 0 and grows: its first samples are small).
// The fixture's inputs held twice as long (every other row): 10 ms holds, as
// the output-error fits of discover see a 200 Hz log (ident/fit_rate.h).
InputHold EveryOtherHold(const InputHold& inputs) {
  std::vector<double> times;
  std::vector<InputVector> values;
  for (int k = 0; k < inputs.size(); k += 2) {
    times.push_back(inputs.time(k));
    values.push_back(inputs.input(k));
  }
  return InputHold(times, values);
}

// hold_scale 2: on EveryOtherHold's inputs, over the same second.
double WorstPerHoldError(const Fixture& f, const Eigen::VectorXd& theta, std::string* worst_at,
                         long* fallback_intervals = nullptr, int hold_scale = 1) {
  std::vector<int> params;
  for (int i = 0; i < theta.size(); ++i) params.push_back(i);
  IntegratorOptions options;
  options.method = IntegratorOptions::Method::kExplicitRungeKutta;
  options.relative_tolerance = 1e-11;
  options.absolute_tolerance = 1e-13;
  options.sensitivity_error_control = false;
  Simulator reference(f.vehicle.model, theta, options, {true, true}, params,
                      SensitivityMethod::kVariationalEquations);
  Simulator per_hold(f.vehicle.model, theta, options, {true, true}, params,
                     SensitivityMethod::kRungeKuttaPerHold);
  Trajectory a, b;
  const InputHold inputs = hold_scale == 1 ? f.inputs : EveryOtherHold(f.inputs);
  EXPECT_TRUE(reference.Run(inputs, 100 / hold_scale, 300 / hold_scale, f.x0, &a))
      << reference.last_error();
  EXPECT_TRUE(per_hold.Run(inputs, 100 / hold_scale, 300 / hold_scale, f.x0, &b))
      << per_hold.last_error();
  if (fallback_intervals) *fallback_intervals = per_hold.fallback_intervals();
  if (a.sensitivities.size() != b.sensitivities.size() || a.sensitivities.empty()) return INFINITY;
  const int columns = static_cast<int>(a.sensitivities[0].cols());
  double worst = 0;
  for (int c = 0; c < columns; ++c) {
    double size = 0, error = 0;
    for (size_t k = 0; k < a.sensitivities.size(); ++k) {
      // The same steps on the state (its error test alone sets them), the
      // arithmetic on a longer vector aside.
      EXPECT_LT((a.states[k] - b.states[k]).norm(), 1e-9 * a.states[k].norm());
      size = std::max(size, a.sensitivities[k].col(c).norm());
      error = std::max(error, (a.sensitivities[k].col(c) - b.sensitivities[k].col(c)).norm());
    }
    if (size == 0) {
      EXPECT_EQ(error, 0) << "column " << c << ": the state does not depend on it";
    } else if (!(error / size <= worst)) {
      worst = error / size;
      *worst_at = "column " + std::to_string(c);
    }
  }
  return worst;
}

TEST(Simulator, OneRungeKuttaStepPerHoldMatchesTheVariationalEquations) {
  const Fixture f = MakeFixture();
  std::string worst_at;
  EXPECT_LT(WorstPerHoldError(f, f.vehicle.parameters.Values(), &worst_at), 1e-5)
      << "at " << worst_at;
}

// The sensitivities' RK4 step leaves for the variational equations only
// where it is not stable, h rho(A) > 2 (dynamics/rk4_stability.h). A strong
// stabilizer bar (k_b = 1, d_u = 0.5 m, inside their bounds; the refits of
// confusion seed 21313 passed such points) couples its tilt into p and q by
// d_u k_b T1 / Ixx, about 320 / s^2, against the tilt's 1 / T_b: on 10 ms
// holds (the fits' of a 200 Hz log) the unscaled row sums exceed the limit
// at every sample, while rho (about 18 / s) stays far below it: every
// interval takes the step, which still matches the variational equations
// to RK4's own error: |R(h lambda) - e^(h lambda)| = (h rho)^5 / 120, 1.6e-6
// a step at h rho = 0.18, at most 1.6e-4 over the 100 steps (measured:
// 7.7e-5 of a column's size). Before the balanced test each interval fell
// back.
TEST(Simulator, NoIntervalLeavesTheRungeKuttaStepWhereItIsStable) {
  const Fixture f = MakeFixture();
  Eigen::VectorXd theta = f.vehicle.parameters.Values();
  theta[f.vehicle.parameters.IndexOrThrow("stabilizer_bar.k_b")] = 1.0;
  theta[f.vehicle.parameters.IndexOrThrow("stabilizer_bar.d_u")] = 0.5;
  std::vector<int> params;
  for (int i = 0; i < theta.size(); ++i) params.push_back(i);
  // How many samples the unscaled row sums and rho itself put past the limit.
  const InputHold inputs = EveryOtherHold(f.inputs);
  IntegratorOptions options;
  options.method = IntegratorOptions::Method::kExplicitRungeKutta;
  Simulator plain(f.vehicle.model, theta, options);
  Trajectory run;
  ASSERT_TRUE(plain.Run(inputs, 50, 150, f.x0, &run)) << plain.last_error();
  VehicleOde ode(f.vehicle.model, theta, params);
  Eigen::MatrixXd A, B;
  int by_row_sums = 0, by_rho = 0;
  for (size_t k = 0; k + 1 < run.states.size(); ++k) {
    const double h = run.times[k + 1] - run.times[k];
    ode.SetInput(run.inputs[k]);
    ASSERT_TRUE(ode.Jacobians(run.times[k], run.states[k].data(), &A, &B));
    by_row_sums += h * ScaledGershgorinBound(A, Eigen::VectorXd()) > 2;
    by_rho += h * SpectralRadius(A) > 2;
  }
  EXPECT_GT(by_row_sums, 90) << "the unscaled test would not have fallen back: the test is moot";
  EXPECT_EQ(by_rho, 0);
  long fallbacks = -1;
  std::string worst_at;
  EXPECT_LT(WorstPerHoldError(f, theta, &worst_at, &fallbacks, 2), 3e-4) << "at " << worst_at;
  EXPECT_EQ(fallbacks, 0);
}

// A stiff mode, the stabilizer bar's time constant at 1 ms (h / T_b = 5, past
// RK4's stability limit 2.79 on the real axis): one RK4 step a hold would
// grow its sensitivities 14-fold a step (1e227 over the second); those
// intervals go to the variational equations.
TEST(Simulator, StiffIntervalsLeaveTheRungeKuttaStep) {
  const Fixture f = MakeFixture();
  Eigen::VectorXd theta = f.vehicle.parameters.Values();
  theta[f.vehicle.parameters.IndexOrThrow("stabilizer_bar.T_b")] = 1e-3;
  std::string worst_at;
  long fallbacks = 0;
  EXPECT_LT(WorstPerHoldError(f, theta, &worst_at, &fallbacks), 1e-5) << "at " << worst_at;
  EXPECT_GT(fallbacks, 0);
}

// The state by one RK4 step per hold (IntegratorOptions::
// one_rk4_step_per_hold, the output-error fits' default) against the
// integrator at a tight tolerance over 1 s, at `theta`: the largest state
// error relative to the state's size.
double WorstRk4StateError(const Fixture& f, const Eigen::VectorXd& theta) {
  IntegratorOptions tight;
  tight.method = IntegratorOptions::Method::kExplicitRungeKutta;
  tight.relative_tolerance = 1e-11;
  tight.absolute_tolerance = 1e-13;
  IntegratorOptions per_hold = tight;
  per_hold.one_rk4_step_per_hold = true;
  Simulator reference(f.vehicle.model, theta, tight);
  Simulator rk4(f.vehicle.model, theta, per_hold);
  Trajectory a, b;
  EXPECT_TRUE(reference.Run(f.inputs, 100, 300, f.x0, &a)) << reference.last_error();
  EXPECT_TRUE(rk4.Run(f.inputs, 100, 300, f.x0, &b)) << rk4.last_error();
  if (a.states.size() != b.states.size() || a.states.empty()) return INFINITY;
  double worst = 0;
  for (size_t k = 0; k < a.states.size(); ++k) {
    worst = std::max(worst, (a.states[k] - b.states[k]).norm() / (1 + a.states[k].norm()));
  }
  return worst;
}

// RK4's error a hold is O(h^5): over the second the states stay within
// 1e-7 of the reference relative to their size (measured: 8.6e-9), far
// inside any noise the fits weigh them by (the logged attitudes' 1e-3 rad).
TEST(Simulator, OneRungeKuttaStepPerHoldForTheStateAgreesWithTheIntegrator) {
  const Fixture f = MakeFixture();
  EXPECT_LT(WorstRk4StateError(f, f.vehicle.parameters.Values()), 1e-7);
}

// The stabilizer bar at T_b = 1 ms (h / T_b = 5, 50 times faster than its
// bounds allow): one RK4 step a hold would grow its tilt's deviation
// 13.7-fold a step (1e227 over the second); the stages' stiffness test hands
// those intervals to the integrator once the deviation shows in them, so the
// state stays within 5e-4 of the reference (measured: 8e-5).
TEST(Simulator, StiffIntervalsLeaveTheRungeKuttaStepOfTheState) {
  const Fixture f = MakeFixture();
  Eigen::VectorXd theta = f.vehicle.parameters.Values();
  theta[f.vehicle.parameters.IndexOrThrow("stabilizer_bar.T_b")] = 1e-3;
  EXPECT_LT(WorstRk4StateError(f, theta), 5e-4);
}

// With stiff_holds_fail (the output-error fits') the stiff bar's intervals
// fail the run, with a message that says where and why, instead of going to
// the integrator; where no interval is stiff (the fixture's vehicle) the run
// is bit for bit the one without the option.
TEST(Simulator, StiffHoldsFailTheRunWhenAskedTo) {
  const Fixture f = MakeFixture();
  IntegratorOptions options;
  options.method = IntegratorOptions::Method::kExplicitRungeKutta;
  options.one_rk4_step_per_hold = true;
  IntegratorOptions refusing = options;
  refusing.stiff_holds_fail = true;
  Trajectory a, b;
  Simulator integrating(f.vehicle.model, f.vehicle.parameters.Values(), options);
  Simulator refused(f.vehicle.model, f.vehicle.parameters.Values(), refusing);
  ASSERT_TRUE(integrating.Run(f.inputs, 100, 300, f.x0, &a)) << integrating.last_error();
  ASSERT_TRUE(refused.Run(f.inputs, 100, 300, f.x0, &b)) << refused.last_error();
  for (size_t k = 0; k < a.states.size(); ++k) EXPECT_EQ(a.states[k], b.states[k]) << k;

  Eigen::VectorXd stiff = f.vehicle.parameters.Values();
  stiff[f.vehicle.parameters.IndexOrThrow("stabilizer_bar.T_b")] = 1e-3;
  Simulator stiff_integrating(f.vehicle.model, stiff, options);
  Simulator stiff_refused(f.vehicle.model, stiff, refusing);
  EXPECT_TRUE(stiff_integrating.Run(f.inputs, 100, 300, f.x0, &a))
      << stiff_integrating.last_error();
  EXPECT_FALSE(stiff_refused.Run(f.inputs, 100, 300, f.x0, &b));
  EXPECT_NE(stiff_refused.last_error().find("integration failed between t = "), std::string::npos)
      << stiff_refused.last_error();
  EXPECT_NE(stiff_refused.last_error().find("a mode faster than the holds can follow"),
            std::string::npos)
      << stiff_refused.last_error();
}

// Sensitivities along the states of a run without them (the output-error
// fit's trial point, accepted) are bit for bit those of a run that
// integrates the states itself: at the nominal vehicle, where those states
// are the plain run's, and with the stiff bar, whose intervals fall back to
// the variational equations, which set the state too (the run is then
// redone integrating). States from another point are not what it is given
// for: with them the sensitivities differ.
TEST(Simulator, SensitivitiesAlongAPlainRunsStatesAreThoseOfAFullRun) {
  const Fixture f = MakeFixture();
  IntegratorOptions options;  // as an output-error fit's segments
  options.method = IntegratorOptions::Method::kExplicitRungeKutta;
  options.relative_tolerance = 1e-7;
  options.absolute_tolerance = 1e-9;
  options.sensitivity_error_control = false;
  // Runs from `from` without sensitivities (its states), and from x0 with
  // them, integrating and along those states.
  struct Runs {
    Trajectory states, full, along;
  };
  auto run = [&](const Eigen::VectorXd& theta, const Eigen::VectorXd& from, bool rk4_state) {
    std::vector<int> params(theta.size());
    for (int i = 0; i < theta.size(); ++i) params[i] = i;
    IntegratorOptions o = options;
    o.one_rk4_step_per_hold = rk4_state;
    Simulator plain(f.vehicle.model, theta, o);
    Simulator sensitive(f.vehicle.model, theta, o, {true, true}, params,
                        SensitivityMethod::kRungeKuttaPerHold);
    Runs r;
    EXPECT_TRUE(plain.Run(f.inputs, 100, 300, from, &r.states)) << plain.last_error();
    EXPECT_TRUE(sensitive.Run(f.inputs, 100, 300, f.x0, &r.full)) << sensitive.last_error();
    EXPECT_TRUE(sensitive.Run(f.inputs, 100, 300, f.x0, &r.along, nullptr, &r.states.states))
        << sensitive.last_error();
    return r;
  };
  Eigen::VectorXd stiff = f.vehicle.parameters.Values();
  stiff[f.vehicle.parameters.IndexOrThrow("stabilizer_bar.T_b")] = 1e-3;
  // The state by the integrator's steps, or by one RK4 step a hold (the
  // fits' default), the same on both runs.
  for (const bool rk4_state : {false, true}) {
    for (const bool falls_back : {false, true}) {
      const Runs r = run(falls_back ? stiff : f.vehicle.parameters.Values(), f.x0, rk4_state);
      ASSERT_EQ(r.full.states.size(), r.along.states.size());
      EXPECT_EQ(r.full.states != r.states.states, falls_back) << "RK4 state " << rk4_state;
      for (size_t k = 0; k < r.full.states.size(); ++k) {
        ASSERT_EQ(r.full.states[k], r.along.states[k]) << "sample " << k;
        ASSERT_EQ(r.full.sensitivities[k], r.along.sensitivities[k]) << "sample " << k;
      }
    }
  }
  // Along states shifted by 1e-6 rad in roll (another start, not this run's):
  // the sensitivities follow the states given.
  Eigen::VectorXd other = f.x0;
  other[kPhi] += 1e-6;
  const Runs shifted = run(f.vehicle.parameters.Values(), other, true);
  EXPECT_NE(shifted.full.sensitivities.back(), shifted.along.sensitivities.back());
}

TEST(Simulator, ReportsBlownUpParametersInsteadOfCrashing) {
  const Fixture f = MakeFixture();
  Eigen::VectorXd theta = f.vehicle.parameters.Values();
  theta[kIxx] = 1e-30;  // a wild trial step of an optimiser
  Simulator simulator(f.vehicle.model, theta);
  Trajectory trajectory;
  EXPECT_FALSE(simulator.Run(f.inputs, 100, 600, f.x0, &trajectory));
  EXPECT_FALSE(simulator.last_error().empty());
}

}  // namespace
}  // namespace coaxid
