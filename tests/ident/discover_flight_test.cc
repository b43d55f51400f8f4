// The closing loop (ident/discovery.h) on short simulated closed-loop flights
// (issue 6, Tests): for every library effect a flight can show, a log with
// that effect in the truth and not in the declared model: discover adds it
// and only it, the held-out error of the channels it drives falls clearly,
// and its parameters come back within 3 std of the truth. Two effects at
// once: both found. No undeclared effect: nothing added over seeds (the
// cluster-robust test keeps its level on flight residuals). An effect outside
// the library: nothing wrong added, its channel reported unexplained, with a
// generic-dictionary candidate.
//
// wake_interference and cg_offset are tested on balance logs
// (discover_test.cc): a flight measures only the total thrust and yaw moment,
// where k_T omega1 omega2 and k_Q omega1 omega2 look like the loss factor
// sigma at the near-equal rotor speeds of hover; and cg_offset's moments
// y_g Z_T, -x_g Z_T are, in near-hover flight with Z_T ~ m g, a constant
// moment like swashplate_bias's (found in flight below), so only the
// balance's varied thrust and swashplate angles tell the two apart.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ident/discovery.h"
#include "tests/ident/discover_test_util.h"

namespace coaxid {
namespace {

// A short closed-loop flight: the shipped scenario's controller, sensors and
// multisine excitation, `seconds` long, moving between two waypoints (so
// velocity-dependent effects show); `low` keeps it 0.3-0.6 m above the floor.
FlightScenario ShortFlight(double seconds, bool low) {
  FlightScenario f = ShippedFlightScenario().flight;
  f.duration_s = seconds;
  f.excitation.start_s = 0.5;
  f.excitation.period_s = 5.0;
  f.excitation.min_hz = 0.2;
  const double h0 = low ? 0.3 : 1.5, h1 = low ? 0.6 : 1.8;
  f.waypoints = {Waypoint{0, 0, 0, h0, 0}, Waypoint{seconds / 2, 0.6, 0.4, h1, 0.2}};
  return f;
}

DiscoveryOptions Options() {
  DiscoveryOptions o;
  o.alpha = 0.01;
  o.fit.num_threads = 2;
  o.fit.noise_relaxations = 1;
  if (getenv("COAXID_TEST_PROGRESS")) {
    o.progress = [](const std::string& l) { fprintf(stderr, "%s\n", l.c_str()); };
    o.fit.progress = o.progress;
  }
  return o;
}

struct FlightRun {
  Vehicle truth;
  DiscoveryResult result;
};

FlightRun DiscoverInFlight(const Effects& effects, bool low, uint64_t seed, double seconds = 10) {
  FlightRun run;
  run.truth = Truth(effects);
  const FlightScenario f = ShortFlight(seconds, low);
  const Log estimation = SimulateFlight(run.truth, f, seed);
  const Log validation = SimulateFlight(run.truth, f, seed + 500);
  // A short balance log fixes the moment and force scales a flight alone
  // leaves free (output_error.h: flight logs fix only ratios such as J_r / Ixx).
  BalanceScenario b;
  b.hold_s = 0.5;
  b.rate_hz = 50;
  const Log balance = SimulateBalance(run.truth, b, seed + 1000);
  run.result = Discover(Nominal(), {MakeEstimationLog(estimation), MakeEstimationLog(balance)},
                        {MakeEstimationLog(validation)}, Options());
  return run;
}

double MeanValidationNrmse(const ModelSnapshot& s, const std::vector<std::string>& channels) {
  double sum = 0;
  for (const std::string& c : channels) sum += s.validation.at(c).nrmse;
  return sum / channels.size();
}

struct EffectCase {
  std::string effect;
  std::map<std::string, double> truth;  // its parameters in the truth
  bool low;                             // flown near the floor
  std::vector<std::string> channels;    // the channels it drives
  uint64_t seed;
};

std::ostream& operator<<(std::ostream& o, const EffectCase& c) { return o << c.effect; }

class DiscoverFlightEffect : public testing::TestWithParam<EffectCase> {};

TEST_P(DiscoverFlightEffect, FindsItAndOnlyIt) {
  const EffectCase& c = GetParam();
  std::map<std::string, ParameterOverride> overrides;
  for (const auto& [name, v] : c.truth) overrides[name] = Value(v);
  const FlightRun run = DiscoverInFlight({{c.effect, overrides}}, c.low, c.seed);
  const DiscoveryResult& r = run.result;
  ASSERT_EQ(r.added, std::vector<std::string>{c.effect});
  // "Clearly": the held-out error of the channels it drives falls by a
  // fifth or more on average (the noise floor bounds how far it can fall).
  const double before = MeanValidationNrmse(r.baseline, c.channels);
  const double after = MeanValidationNrmse(r.final, c.channels);
  EXPECT_LT(after, 0.8 * before) << "held-out nrmse " << before << " -> " << after;
  for (const auto& [name, v] : c.truth) ExpectWithinThreeStd(r, run.truth, c.effect + "." + name);
}

INSTANTIATE_TEST_SUITE_P(
    Library, DiscoverFlightEffect,
    testing::Values(EffectCase{"gyroscopic", {{"J_r", 3e-4}}, false, {"p", "q"}, 61},
                    EffectCase{"rotor_damping", {{"k_pq", 2e-3}}, false, {"p", "q"}, 62},
                    EffectCase{"ground_effect", {{"k_ge", 1.0}}, true, {"w", "az"}, 63},
                    EffectCase{"rotor_drag", {{"k_h", 3e-4}}, false, {"u", "v", "ax", "ay"}, 64},
                    EffectCase{"swashplate_bias",
                               {{"b_x", 0.015}, {"b_y", -0.01}},
                               false,
                               {"p", "q", "phi", "theta"},
                               65},
                    EffectCase{"cg_offset",
                               {{"x_g", 4e-3}, {"y_g", -3e-3}},
                               false,
                               {"p", "q", "phi", "theta"},
                               67},
                    EffectCase{"wind",
                               {{"wn", 2.0}, {"we", -1.5}, {"wd", 0.0}},
                               false,
                               {"u", "v", "ax", "ay"},
                               66}),
    [](const testing::TestParamInfo<EffectCase>& info) { return info.param.effect; });

TEST(DiscoverFlight, TwoEffectsAreBothFound) {
  const FlightRun run = DiscoverInFlight(
      {{"gyroscopic", {{"J_r", Value(1e-4)}}}, {"wind", {{"wn", Value(2.0)}, {"we", Value(-1.5)}}}},
      false, 71);
  std::vector<std::string> added = run.result.added;
  std::sort(added.begin(), added.end());
  EXPECT_EQ(added, (std::vector<std::string>{"gyroscopic", "wind"}));
}

TEST(DiscoverFlight, NothingAddedWithoutAnUndeclaredEffect) {
  // Family-wise alpha = 0.01 per run: over 3 seeds a false alarm has
  // probability ~3 % if the test keeps its level, and ~1 per seed with the
  // white-noise F-test this replaced (measured, README).
  int false_alarms = 0;
  for (uint64_t seed = 81; seed < 84; ++seed) {
    const FlightRun run = DiscoverInFlight({}, false, seed, 8);
    false_alarms += !run.result.added.empty();
  }
  EXPECT_EQ(false_alarms, 0);
}

TEST(DiscoverFlight, EffectOutsideTheLibraryIsReportedUnexplained) {
  // The yaw-rate gyro reads 0.05 rad/s high (5 x its noise): a sensor bias,
  // which no library effect models (they all act on forces, moments or the
  // air velocity, none on what a sensor reports), written into the truth's
  // sensor model only. r and the yaw angle psi then disagree.
  const Vehicle truth = Truth({});
  FlightScenario f = ShortFlight(8, false);
  f.bias["r"] = 0.05;
  auto log = [&](uint64_t seed) { return MakeEstimationLog(SimulateFlight(truth, f, seed)); };
  const DiscoveryResult r = Discover(Nominal(), {log(91)}, {log(92)}, Options());
  EXPECT_TRUE(r.added.empty()) << "added " << (r.added.empty() ? "" : r.added.front());
  bool yaw = false;
  for (const UnexplainedChannel& u : r.unexplained) {
    if (u.channel != "r") continue;
    yaw = true;
    // Step 7: the generic dictionary offers terms for it (not added).
    EXPECT_FALSE(u.generic.terms.empty()) << u.why;
  }
  EXPECT_TRUE(yaw) << "r not reported unexplained";
  if (getenv("COAXID_TEST_PROGRESS")) {
    for (const ChannelResidualTest& t : r.final.residual_tests) {
      fprintf(stderr, "%s LB p %.3g rms %.3g noise %.3g\n", t.channel.c_str(), t.ljung_box_p, t.rms, t.noise_std);
    }
  }
}

}  // namespace
}  // namespace coaxid
