// Experiment design: the criterion's gradient, the band-shaped multisine and
// its scenario file, balance holds that make the paper's method work, and an
// excitation design that keeps the pilot's limits.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "core/errors.h"
#include "experiments/design/balance_design.h"
#include "experiments/design/design_report.h"
#include "experiments/design/excitation_design.h"
#include "experiments/simulation/excitation.h"
#include "experiments/simulation/simulate_experiment.h"
#include "ident/free_parameters.h"
#include "tests/random_truth.h"

namespace coaxid {
namespace {

Vehicle Nominal() { return LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml"); }

Eigen::MatrixXd RandomPsd(int n, int rank, std::mt19937_64* rng) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd A(n, rank);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < rank; ++j) A(i, j) = normal(*rng);
  }
  return A * A.transpose();
}

// A prediction's bookkeeping around a given information matrix.
PredictedPrecision FakePrecision(const Eigen::MatrixXd& information) {
  PredictedPrecision p;
  const Vehicle v = Nominal();
  p.parameters = v.parameters;
  const FreeParameters free(v.parameters);
  p.names.assign(free.names().begin(), free.names().begin() + information.rows());
  p.scales.resize(information.rows());  // scaled coordinates: value / |value| = +-1
  for (int k = 0; k < information.rows(); ++k) p.scales[k] = std::fabs(p.parameters.Value(p.names[k]));
  return WithInformation(p, information, information);
}

TEST(DesignCriterion, GradientEqualsFiniteDifferences) {
  std::mt19937_64 rng(3);
  const int P = 6;
  const Eigen::MatrixXd M = RandomPsd(P, P + 2, &rng);
  std::vector<Eigen::MatrixXd> directions = {RandomPsd(P, 1, &rng), RandomPsd(P, 3, &rng)};
  for (DesignCriterion::Kind kind : {DesignCriterion::Kind::kD, DesignCriterion::Kind::kA}) {
    DesignCriterion criterion;
    criterion.kind = kind;
    criterion.parameters = {"beta", "Cx", "sigma0"};
    const CriterionOnInformation c(criterion, FakePrecision(M));
    const Eigen::VectorXd g = c.Gradient(M, directions);
    for (size_t k = 0; k < directions.size(); ++k) {
      const double h = 1e-6;
      const double fd =
          (c.Value(M + h * directions[k]) - c.Value(M - h * directions[k])) / (2 * h);
      EXPECT_NEAR(g[k], fd, 1e-5 * std::max(1.0, std::fabs(fd))) << criterion.Name() << k;
    }
  }
}

TEST(DesignCriterion, IsTheRelativeCovarianceOfTheNamedParameters) {
  std::mt19937_64 rng(4);
  const Eigen::MatrixXd M = RandomPsd(5, 9, &rng);
  const PredictedPrecision p = FakePrecision(M);
  const Eigen::MatrixXd C = M.inverse();
  // Scaled coordinates are value / scale = +-1 here: relative = scaled.
  DesignCriterion a;
  a.kind = DesignCriterion::Kind::kA;
  a.parameters = {"alpha", "sigma0"};
  EXPECT_NEAR(CriterionOnInformation(a, p).Value(M), C(0, 0) + C(2, 2), 1e-9 * C(0, 0));
  DesignCriterion d = a;
  d.kind = DesignCriterion::Kind::kD;
  const double log_det = std::log(C(0, 0) * C(2, 2) - C(0, 2) * C(2, 0));
  EXPECT_NEAR(CriterionOnInformation(d, p).Value(M), log_det, 1e-8);
  d.parameters = {"d_not_a_parameter"};
  EXPECT_THROW(CriterionOnInformation(d, p), InputError);
}

// Each band of a shaped multisine carries the rms asked of it, on harmonics
// no other input uses; the quiet windows silence it.
TEST(ExcitationBands, EachBandCarriesItsRmsOnItsOwnHarmonics) {
  Excitation e;
  e.period_s = 20;
  e.start_s = 0;
  e.bands = {{0.1, 0.5, {{"omega1", 2.0}, {"delta_cy", 0.01}}},
             {0.5, 1.5, {{"omega1", 1.0}, {"omega2", 3.0}, {"delta_cx", 0.02}}}};
  const ExcitationSignal signal(e);
  const double expected[2][4] = {{2.0, 0, 0, 0.01}, {1.0, 3.0, 0.02, 0}};
  const int n = 20000, harmonics = 40;  // samples over one period; harmonics of 1/20 Hz examined
  std::vector<InputVector> u(n);
  for (int i = 0; i < n; ++i) u[i] = signal.At(20.0 * i / n);
  // amplitude^2 of every harmonic of every input.
  std::vector<std::vector<double>> a2(4, std::vector<double>(harmonics, 0.0));
  for (int c = 0; c < 4; ++c) {
    double peak = 0;
    for (int i = 0; i < n; ++i) peak = std::max(peak, std::fabs(u[i][c]));
    EXPECT_NEAR(signal.Peak(c), peak, 1e-3 * peak + 1e-12) << c;
    double band_power[2] = {0, 0};
    for (int h = 1; h < harmonics; ++h) {
      double re = 0, im = 0;
      for (int i = 0; i < n; ++i) {
        re += u[i][c] * std::cos(2 * M_PI * h * i / n) * 2.0 / n;
        im += u[i][c] * std::sin(2 * M_PI * h * i / n) * 2.0 / n;
      }
      a2[c][h] = re * re + im * im;
      const double f = h / 20.0;
      if (f >= 0.1 && f <= 0.5) band_power[0] += a2[c][h] / 2;
      if (f > 0.5 && f <= 1.5) band_power[1] += a2[c][h] / 2;
    }
    for (int b = 0; b < 2; ++b) {
      EXPECT_NEAR(std::sqrt(band_power[b]), expected[b][c], 1e-6 + 1e-6 * expected[b][c])
          << "input " << c << " band " << b;
    }
  }
  // No harmonic is shared by two inputs (the inputs are uncorrelated).
  for (int h = 1; h < harmonics; ++h) {
    int users = 0;
    for (int c = 0; c < 4; ++c) users += a2[c][h] > 1e-16;
    EXPECT_LE(users, 1) << "harmonic " << h;
  }
  // Quiet windows: nothing inside, the same signal beyond the ramps.
  Excitation quiet = e;
  quiet.quiet = {{5.0, 7.0}};
  const ExcitationSignal gated(quiet);
  for (double t : {5.0, 6.0, 7.0}) EXPECT_EQ(gated.At(t)[0], 0.0);
  for (double t : {4.0, 8.0, 12.0}) EXPECT_EQ(gated.At(t)[0], signal.At(t)[0]);
  EXPECT_LT(std::fabs(gated.At(4.75)[0]), std::fabs(signal.At(4.75)[0]));
}

std::vector<Scenario> BalanceOnlyPlan(bool with_swashplate) {
  Scenario balance;
  balance.kind = Scenario::Kind::kBalance;
  balance.name = "plan";
  balance.balance.hold_s = 0.5;
  balance.balance.rate_hz = 50;
  if (!with_swashplate) balance.balance.delta_cx = balance.balance.delta_cy = {0.0};
  return {balance};
}

// A campaign without swashplate holds cannot separate beta from Cz_beta
// (the swashplate condition of Lemma 1); the designed holds fix that, and
// adding holds only adds information: no predicted std grows.
TEST(BalanceDesign, AddsTheHoldsTheLinearMethodNeedsAndNoStdGrows) {
  const Vehicle vehicle = RandomTruth(Nominal(), 7);
  DesignCriterion criterion;
  criterion.parameters = {"beta", "Cz", "sigma0"};
  BalanceDesignOptions options;
  options.add_holds = 3;
  options.output_error.segment_schedule_s = {1.0};
  const BalanceDesign design =
      DesignBalanceHolds(vehicle, BalanceOnlyPlan(false), criterion, options);
  ASSERT_TRUE(design.has_lemma_before);
  EXPECT_FALSE(design.lemma_before.Exciting());
  EXPECT_TRUE(design.lemma_after.Exciting()) << design.lemma_after.message;
  ASSERT_EQ(design.added.size(), 3u);
  EXPECT_LT(design.criterion_after, design.criterion_before);
  for (size_t k = 0; k < design.after.names.size(); ++k) {
    ASSERT_EQ(design.after.names[k], design.before.names[k]);
    // A balance does not see the inertias or the body's side drag; d only
    // through swashplate holds, which the plan has none of.
    if (!std::isfinite(design.before.identifiability.std[k])) continue;
    EXPECT_LE(design.after.identifiability.std[k], design.before.identifiability.std[k] * (1 + 1e-9))
        << design.after.names[k];
  }
  // The designed campaign's file reads back with the added holds.
  const Scenario& designed = design.designed[design.balance_index];
  const Scenario parsed = ParseScenario(DesignedScenarioYaml("balance", designed), "designed.yaml");
  ASSERT_EQ(parsed.balance.holds.size(), designed.balance.holds.size());
  for (size_t i = 0; i < parsed.balance.holds.size(); ++i) {
    EXPECT_EQ(parsed.balance.holds[i], designed.balance.holds[i]);
  }
}

// A 20 s flight with a waypoint change: the designed excitation, flown in
// the closed loop, stays within the limits, improves the criterion on the
// plan, and its scenario file flies the same flight.
// The designed flight's peaks against the limits the design applied.
void ExpectWithinLimits(const ExcitationDesign& design) {
  const FlightEnvelope& e = design.designed_run.envelopes[0];
  EXPECT_LE(e.max_attitude_rad, design.limits.max_attitude_rad);
  EXPECT_LE(e.max_rotor_speed_deviation_rad_s, design.limits.max_rotor_speed_deviation_rad_s);
  EXPECT_LE(e.max_swashplate_rad, design.limits.max_swashplate_rad);
  EXPECT_LE(e.max_height_deviation_m, design.limits.max_height_deviation_m);
}

// The designed scenario file, read back and flown, is the designed flight.
Scenario ExpectTheFileFliesTheDesign(const Vehicle& vehicle, const ExcitationDesign& design) {
  const Scenario parsed =
      ParseScenario(DesignedScenarioYaml("flight", design.designed[0]), "designed.yaml");
  FlightScenario replay = design.designed[0].flight;
  replay.excitation = parsed.flight.excitation;
  const Log a = SimulateFlight(vehicle, design.designed[0].flight, design.designed[0].seed);
  const Log b = SimulateFlight(vehicle, replay, design.designed[0].seed);
  EXPECT_EQ(a.values, b.values);
  return parsed;
}

TEST(ExcitationDesign, KeepsTheLimitsAndImprovesOnThePlan) {
  const Vehicle vehicle = RandomTruth(Nominal(), 19);
  Scenario flight = LoadScenario(std::string(COAXID_SOURCE_DIR) + "/configs/scenarios/flight.yaml");
  flight.flight.duration_s = 20;
  flight.flight.waypoints = {Waypoint{0, 0, 0, 1.5, 0}, Waypoint{10, 0.3, 0, 1.7, 0.1}};
  flight.flight.excitation.period_s = 10;
  DesignCriterion criterion;
  criterion.parameters = {"Cz", "sigma0"};
  ExcitationDesignOptions options;
  options.max_rounds = 2;
  options.bands = {{0.2, 1.0}, {1.0, 4.0}};
  options.output_error.segment_schedule_s = {1.0};
  options.limits.max_attitude_rad = 0.05;
  const ExcitationDesign design = DesignExcitation(vehicle, {flight}, criterion, options);
  ExpectWithinLimits(design);
  EXPECT_LT(design.criterion_after, design.criterion_before);
  const Scenario parsed = ExpectTheFileFliesTheDesign(vehicle, design);
  EXPECT_EQ(parsed.flight.excitation.quiet.size(), 1u);  // around the waypoint change
}


// The 3211 option: a pulse width that fits the flight (a cycle of the four
// inputs is 40 widths; 0.5 s does not fit 18 s of excitation), the limits
// kept, and the file read back flies the designed flight.
TEST(ExcitationDesign, A3211KeepsTheLimitsAndFitsItsCycleInTheFlight) {
  const Vehicle vehicle = RandomTruth(Nominal(), 23);
  Scenario flight = LoadScenario(std::string(COAXID_SOURCE_DIR) + "/configs/scenarios/flight.yaml");
  flight.flight.duration_s = 20;
  flight.flight.waypoints = {Waypoint{0, 0, 0, 1.5, 0}, Waypoint{10, 0.3, 0, 1.7, 0.1}};
  DesignCriterion criterion;
  criterion.parameters = {"Cz", "sigma0"};
  ExcitationDesignOptions options;
  options.excitation = Excitation::Type::k3211;
  options.pulse_widths_s = {0.1, 0.2, 0.5};
  options.max_rounds = 1;
  options.output_error.segment_schedule_s = {1.0};
  options.limits.max_attitude_rad = 0.05;
  const ExcitationDesign design = DesignExcitation(vehicle, {flight}, criterion, options);
  EXPECT_TRUE(design.pulse_s == 0.1 || design.pulse_s == 0.2) << design.pulse_s;
  const Excitation& e = design.designed[0].flight.excitation;
  EXPECT_EQ(e.type, Excitation::Type::k3211);
  EXPECT_EQ(e.pulse_s, design.pulse_s);
  ExpectWithinLimits(design);
  ASSERT_EQ(design.components.size(), 4u);
  for (const auto& c : design.components) {
    EXPECT_NEAR(c.designed_level, e.amplitude.at(c.channel), 1e-12 * c.designed_level);
  }
  ExpectTheFileFliesTheDesign(vehicle, design);

  options.pulse_widths_s = {0.5, 1.0};  // no cycle fits
  EXPECT_THROW(DesignExcitation(vehicle, {flight}, criterion, options), ComputationError);
}

}  // namespace
}  // namespace coaxid
