// Flight-path reconstruction (ident/kinematic/flight_path_reconstruction.h)
// on simulated closed-loop flights whose sensors carry known errors: gyro
// and accelerometer biases (the library's measurement effects in the truth),
// scale factors applied to the logged IMU columns, and the positions,
// velocities and attitude logged 20 ms late (4 rows at 200 Hz). The
// reconstruction, which knows nothing of the vehicle, recovers every bias,
// scale factor and the time offset within 3 std; with clean sensors it finds
// them all within 3 std of 0; the corrected log has the errors removed. The
// x and y accelerometer scale factors, which a near-hover flight does not
// fix, are held at 0 and said so.
#include "ident/kinematic/flight_path_reconstruction.h"

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/errors.h"
#include "experiments/simulation/scenario.h"
#include "experiments/simulation/simulate_experiment.h"

namespace coaxid {
namespace {

struct SensorErrors {
  std::map<std::string, double> bias;   // b_p .. b_az
  std::map<std::string, double> scale;  // s_p .. s_az
  int late_rows = 0;                    // positions, velocities, attitude late by this many rows
};

// A 30 s flight of the shipped scenario's truth at 200 Hz with these sensor errors.
Log FlightWithSensorErrors(const SensorErrors& errors, uint64_t seed) {
  const VehicleConfig config =
      LoadVehicleConfig(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
  Scenario scenario =
      LoadScenario(std::string(COAXID_SOURCE_DIR) + "/configs/scenarios/flight.yaml");
  std::map<std::string, ParameterOverride> gyro, accel;
  for (const char* b : {"b_p", "b_q", "b_r"}) gyro[b].value = errors.bias.count(b) ? errors.bias.at(b) : 0;
  for (const char* b : {"b_ax", "b_ay", "b_az"}) {
    accel[b].value = errors.bias.count(b) ? errors.bias.at(b) : 0;
  }
  scenario.truth_effects = {{"gyro_bias", gyro}, {"accel_bias", accel}};
  scenario.flight.duration_s = 30;
  Log log = SimulateFlight(MakeTruthVehicle(config, scenario), scenario.flight, seed);
  // Scale factors on the logged IMU: m = (1 + s) true + b = (1 + s) (m0 - b) + b.
  for (const auto& [name, s] : errors.scale) {
    const std::string column = name.substr(2);  // "s_p" -> "p"
    const double b = errors.bias.count("b_" + column) ? errors.bias.at("b_" + column) : 0;
    std::vector<double> v = log.Column(column);
    for (double& x : v) x = (1 + s) * (x - b) + b;
    log.SetColumn(column, v);
  }
  // Late channels: row k logs the value of row k - late_rows.
  if (errors.late_rows > 0) {
    for (const char* column : {"x", "y", "z", "u", "v", "w", "phi", "theta", "psi"}) {
      const std::vector<double> v = log.Column(column);
      std::vector<double> late = v;
      for (size_t k = 0; k < v.size(); ++k) {
        late[k] = v[k >= static_cast<size_t>(errors.late_rows) ? k - errors.late_rows : 0];
      }
      log.SetColumn(column, late);
    }
  }
  return log;
}

int IndexOf(const KinematicResult& r, const std::string& name) {
  for (size_t k = 0; k < r.names.size(); ++k) {
    if (r.names[k] == name) return static_cast<int>(k);
  }
  ADD_FAILURE() << name << " unknown";
  return 0;
}

// Every estimated sensor error within 3 std of its truth; the only ones held
// are the x and y accelerometer scale factors, which a near-hover flight
// (ax, ay near 0) does not fix.
void ExpectRecovered(const KinematicResult& r, const std::map<std::string, double>& truth) {
  for (size_t k = 0; k < r.names.size(); ++k) {
    const std::string& name = r.names[k];
    const double t = truth.count(name) ? truth.at(name) : 0.0;
    if (!r.estimated[k]) {
      EXPECT_TRUE(name == "s_ax" || name == "s_ay") << name << " held";
      continue;
    }
    ASSERT_GT(r.std[k], 0) << name;
    EXPECT_NEAR(r.estimate[k], t, 3 * r.std[k])
        << name << " = " << r.estimate[k] << " +- " << r.std[k] << ", truth " << t;
  }
}

TEST(FlightPathReconstruction, RecoversBiasesScaleFactorsAndA20msOffset) {
  SensorErrors e;
  e.bias = {{"b_p", 0.02}, {"b_q", -0.015}, {"b_r", 0.01},
            {"b_ax", 0.15}, {"b_ay", -0.1}, {"b_az", 0.2}};
  e.scale = {{"s_p", 0.03}, {"s_q", -0.02}, {"s_r", 0.04},
             {"s_ax", 0.02}, {"s_ay", -0.03}, {"s_az", 0.01}};
  e.late_rows = 4;  // 20 ms at 200 Hz
  const Log log = FlightWithSensorErrors(e, 31);
  const KinematicResult r = ReconstructFlightPath({MakeEstimationLog(log)}, KinematicOptions{});
  std::map<std::string, double> truth = {{"tau", 0.020}};
  for (const auto& [name, v] : e.bias) truth[name] = v;
  for (const auto& [name, v] : e.scale) truth[name] = v;
  ExpectRecovered(r, truth);
  for (const char* name : {"b_p", "b_q", "b_r", "s_p", "s_q", "s_r", "s_az", "tau"}) {
    EXPECT_TRUE(r.estimated[IndexOf(r, name)]) << name;
  }
  // Informative: the time offset to a millisecond, the gyro biases and the
  // x, y accelerometer biases to a fifth of their size. b_az is not: with az
  // near -g all flight, b_az and s_az g move the reading alike (their
  // correlation says so).
  EXPECT_LT(r.std[IndexOf(r, "tau")], 1e-3);
  for (const char* name : {"b_p", "b_q", "b_r", "b_ax", "b_ay"}) {
    const int k = IndexOf(r, name);
    EXPECT_LT(r.std[k], 0.2 * std::fabs(truth[name])) << name;
  }
  EXPECT_GT(std::fabs(r.correlation(IndexOf(r, "b_az"), IndexOf(r, "s_az"))), 0.9);
  // The corrected log: IMU with the estimated errors removed, the late
  // channels moved back. Its reconstruction finds nothing left.
  const KinematicResult again =
      ReconstructFlightPath({MakeEstimationLog(CorrectedLog(log, r))}, KinematicOptions{});
  for (size_t k = 0; k < again.names.size(); ++k) {
    if (!again.estimated[k]) continue;
    EXPECT_LT(std::fabs(again.estimate[k]), 3 * again.std[k])
        << again.names[k] << " after correction: " << again.estimate[k] << " +- " << again.std[k];
  }
}

// The threads default to every core, so the answer must not depend on
// them: on one thread and on three, the same estimates and stds (to
// rounding: Ceres may sum a parallel evaluation in another order).
TEST(FlightPathReconstruction, TheSameOnOneThreadAndOnThree) {
  SensorErrors e;
  e.bias = {{"b_p", 0.02}, {"b_ax", 0.15}};
  e.late_rows = 4;
  const EstimationLog log = MakeEstimationLog(FlightWithSensorErrors(e, 33));
  KinematicOptions one, three;
  one.num_threads = 1;
  three.num_threads = 3;
  const KinematicResult a = ReconstructFlightPath({log}, one);
  const KinematicResult b = ReconstructFlightPath({log}, three);
  ASSERT_GT(a.iterations, 0);
  EXPECT_EQ(a.estimated, b.estimated);
  EXPECT_EQ(a.iterations, b.iterations);
  for (int k = 0; k < a.estimate.size(); ++k) {
    EXPECT_NEAR(a.estimate[k], b.estimate[k], 1e-9 * (1 + std::fabs(a.estimate[k])))
        << a.names[k];
    EXPECT_NEAR(a.std[k], b.std[k], 1e-9 * (1 + a.std[k])) << a.names[k];
  }
}

TEST(FlightPathReconstruction, CleanSensorsGiveNothing) {
  const KinematicResult r =
      ReconstructFlightPath({MakeEstimationLog(FlightWithSensorErrors({}, 32))}, KinematicOptions{});
  ExpectRecovered(r, {});
  EXPECT_TRUE(r.estimated[IndexOf(r, "tau")]);
}

TEST(FlightPathReconstruction, RefusesLogsItCannotUse) {
  Log log = FlightWithSensorErrors({}, 33);
  std::vector<double> ax = log.Column("ax");
  ax[100] = std::nan("");
  log.SetColumn("ax", ax);
  try {
    ReconstructFlightPath({MakeEstimationLog(log)}, KinematicOptions{});
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("row 101, column 'ax'"), std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace coaxid
