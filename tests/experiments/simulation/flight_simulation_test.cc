// Closed-loop flight: the controller holds the (open-loop unstable) hover for
// 60 s under excitation and sensor noise, and the logged outputs are the
// truth plus noise of the configured size.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "core/input_hold.h"
#include "core/statistics.h"
#include "dynamics/trim.h"
#include "experiments/simulation/simulate_experiment.h"
#include "tests/typical_effect.h"

namespace coaxid {
namespace {

Vehicle ReferenceVehicle() {
  return LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
}

TEST(FlightSimulation, StaysBoundedForSixtySeconds) {
  const Vehicle vehicle = ReferenceVehicle();
  Scenario scenario = LoadScenario(std::string(COAXID_SOURCE_DIR) + "/configs/scenarios/flight.yaml");
  const Vehicle truth = MakeTruthVehicle(vehicle.config, scenario);
  const Log log = SimulateScenario(truth, scenario);
  ASSERT_EQ(log.NumRows(), 12001);
  // Bounded: near hover means small attitude, position within a metre of the
  // waypoints (0..0.5 m), height within 0.5 m of 1.5-1.8 m.
  for (const char* angle : {"phi", "theta"}) {
    for (double a : log.Column(angle)) ASSERT_LT(std::fabs(a), 0.2) << angle;
  }
  for (double x : log.Column("x")) ASSERT_LT(std::fabs(x - 0.25), 1.0);
  for (double y : log.Column("y")) ASSERT_LT(std::fabs(y - 0.25), 1.0);
  for (double z : log.Column("z")) ASSERT_TRUE(z < -1.0 && z > -2.3) << z;
  // The excitation really moves the inputs (persistent excitation needs it).
  EXPECT_GT(StdDev(log.Column("delta_cx")), 0.005);
  EXPECT_GT(StdDev(log.Column("omega1")), 1.0);
}

TEST(FlightSimulation, ThreeTwoOneOneAndEffectsStayBounded) {
  const Vehicle vehicle = ReferenceVehicle();
  Scenario scenario =
      LoadScenario(std::string(COAXID_SOURCE_DIR) + "/configs/scenarios/flight_3211.yaml");
  // Every effect of the library on at once, at its typical strength: the
  // controller must still hold the vehicle.
  for (const EffectInfo& info : EffectLibrary()) {
    std::map<std::string, ParameterOverride> overrides;
    for (const auto& p : info.parameters) overrides[p.name].value = p.typical;
    scenario.truth_effects.emplace_back(info.name, overrides);
  }
  const Vehicle truth = MakeTruthVehicle(vehicle.config, scenario);
  const Log log = SimulateScenario(truth, scenario);
  for (const char* angle : {"phi", "theta"}) {
    for (double a : log.Column(angle)) ASSERT_LT(std::fabs(a), 0.3) << angle;
  }
}

// The default flight integrator (explicit Runge-Kutta, rtol 1e-7) against a reference run
// of CVODE's Adams method at rtol 1e-12: the same closed-loop flight, the same noise draws.
// Bound: the local tolerance is tol = 1e-7 |x| + 1e-9 with |x| <= 2 (height 1.5-1.8 m), and
// the closed loop forgets an error within its slowest time constant, about 1 s = 200
// intervals, so errors of at most 200 local tolerances accumulate: 4.0e-5. A method that
// lost accuracy at every restart, or an interval stepped with the wrong input, would be off
// by far more (one 5 ms interval of a wrong swashplate angle moves q by ~1e-4 rad/s). Adams
// at rtol 1e-7 (the integrator it replaced) is held to the same bound.
TEST(FlightSimulation, TheDefaultIntegratorMatchesATightReference) {
  const Vehicle vehicle = ReferenceVehicle();
  Scenario scenario = LoadScenario(std::string(COAXID_SOURCE_DIR) + "/configs/scenarios/flight.yaml");
  scenario.flight.duration_s = 20;
  const Vehicle truth = MakeTruthVehicle(vehicle.config, scenario);
  IntegratorOptions reference;
  reference.relative_tolerance = 1e-12;
  reference.absolute_tolerance = 1e-14;
  std::vector<Eigen::VectorXd> exact, fast, adams;
  SimulateFlight(truth, scenario.flight, scenario.seed, reference, &exact);
  SimulateFlight(truth, scenario.flight, scenario.seed, FlightSimulationIntegrator(), &fast);
  IntegratorOptions adams_options;
  adams_options.relative_tolerance = 1e-7;
  adams_options.absolute_tolerance = 1e-9;
  SimulateFlight(truth, scenario.flight, scenario.seed, adams_options, &adams);
  ASSERT_EQ(fast.size(), exact.size());
  double fast_error = 0.0, adams_error = 0.0;
  for (size_t k = 0; k < exact.size(); ++k) {
    fast_error = std::max(fast_error, (fast[k] - exact[k]).cwiseAbs().maxCoeff());
    adams_error = std::max(adams_error, (adams[k] - exact[k]).cwiseAbs().maxCoeff());
  }
  std::printf("max state error vs the reference: explicit RK %.3g, Adams %.3g\n", fast_error,
              adams_error);
  EXPECT_LT(fast_error, 4.0e-5);
  EXPECT_LT(adams_error, 4.0e-5);
}

// Noise-free sensors log the truth: the accelerometer equals the model's
// specific force (decision 7) and hover is held at the trim with no excitation.
TEST(FlightSimulation, NoiseFreeHoverStaysAtTrim) {
  const Vehicle vehicle = ReferenceVehicle();
  FlightScenario s;
  s.duration_s = 5;
  s.excitation.type = Excitation::Type::kNone;
  s.noise_std.clear();
  const Log log = SimulateFlight(vehicle, s, 1);
  const HoverTrim trim = TrimHover(vehicle.model, vehicle.parameters.Values(), 1.5);
  // Starting exactly at the trim with perfect sensors, nothing moves: the
  // drift over 5 s is bounded by the integrator tolerance (rtol 1e-7).
  for (int k = 0; k < log.NumRows(); ++k) {
    ASSERT_NEAR(log.Column("z")[k], -1.5, 1e-6);
    ASSERT_NEAR(log.Column("omega1")[k], trim.input[0], 1e-4);
    ASSERT_NEAR(log.Column("az")[k], -vehicle.parameters.Value("g"), 1e-6);
  }
}

// A truth with measurement effects (gyro_bias, accel_bias) logs the biased
// readings in every channel the effect names, the states included (the
// controller flies on them): at row 0, the trim, noise-free sensors read
// p, q, r = the gyro biases, and the specific force of the unbiased model at
// the trim state with row 0's logged inputs (the controller already answers
// the biased rates) plus the accelerometer biases.
TEST(FlightSimulation, MeasurementEffectsAreWhatTheSensorsLog) {
  const Vehicle vehicle = ReferenceVehicle();
  Scenario scenario;
  scenario.flight.duration_s = 1;
  scenario.flight.excitation.type = Excitation::Type::kNone;
  scenario.flight.noise_std.clear();
  // The library's typical biases: b_p 0.02, b_q -0.015, b_r 0.01 rad/s; b_ax 0.15,
  // b_ay -0.1, b_az 0.2 m/s^2.
  scenario.truth_effects = {TypicalEffect("gyro_bias"), TypicalEffect("accel_bias")};
  const Vehicle truth = MakeTruthVehicle(vehicle.config, scenario);
  const Log log = SimulateFlight(truth, scenario.flight, 1);
  EXPECT_NEAR(log.Column("p")[0], 0.02, 1e-12);
  EXPECT_NEAR(log.Column("q")[0], -0.015, 1e-12);
  EXPECT_NEAR(log.Column("r")[0], 0.01, 1e-12);
  EXPECT_NEAR(log.Column("phi")[0], 0.0, 1e-12);
  const Eigen::VectorXd theta = vehicle.parameters.Values();
  const HoverTrim trim = TrimHover(vehicle.model, theta, 1.5);
  const InputVector u0 = InputHold::FromLog(log).input(0);
  const Vec3<double> f = vehicle.model.SpecificForce(theta.data(), trim.state.data(), u0.data());
  EXPECT_NEAR(log.Column("ax")[0], f[0] + 0.15, 1e-9);
  EXPECT_NEAR(log.Column("ay")[0], f[1] - 0.1, 1e-9);
  EXPECT_NEAR(log.Column("az")[0], f[2] + 0.2, 1e-9);
  // The controller answers the biased rates at once: row 0's swashplate is
  // off the trim (else the check above would not see the inputs).
  EXPECT_NE(u0[kDeltaCx], trim.input[kDeltaCx]);
}

}  // namespace
}  // namespace coaxid
