// Closed-loop flight: the controller holds the (open-loop unstable) hover for
// 60 s under excitation and sensor noise, and the logged outputs are the
// truth plus noise of the configured size.
#include <cmath>

#include <gtest/gtest.h>

#include "core/statistics.h"
#include "dynamics/trim.h"
#include "experiments/simulation/simulate_experiment.h"

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

}  // namespace
}  // namespace coaxid
