// The closing loop (ident/discover/discovery.h) on short simulated closed-loop flights
// (issue 6, Tests): for every library effect a flight can show, a log with
// that effect in the truth and not in the declared model: discover adds it
// and only it, the held-out error of the channels it drives falls clearly,
// and its parameters come back within 3 std of the truth. Two effects at
// once: both found. No undeclared effect: nothing added over seeds (the
// cluster-robust test keeps its level on flight residuals). An effect outside
// the library: nothing wrong added, its channel reported unexplained, with a
// generic-dictionary candidate.
//
// wake_interference is tested on balance logs (discovery_test.cc, with
// cg_offset, found in both) and on a flight beside a balance log: a flight
// measures only the total thrust and yaw moment, where k_T omega1 omega2 and
// k_Q omega1 omega2 look like the loss factor sigma at the near-equal rotor
// speeds of hover; only the balance's per-rotor loads and single-rotor holds
// separate them. rotor_drag needs a
// flight designed for it: near hover the body drag absorbs it, in fast
// transits with climbs discover finds it (its two tests below).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ident/discover/discovery.h"
#include "tests/ident/discover/discovery_test_util.h"

namespace coaxid {
namespace {

// A short closed-loop flight: the shipped scenario's controller, sensors and
// multisine excitation, `seconds` long, to a waypoint `reach` metres away
// (so that velocity-dependent effects show; the position loop flies it at up
// to ~1 m/s for 2 m) from t = 1 s; `low` keeps it 0.3-0.6 m above the floor.
FlightScenario ShortFlight(double seconds, bool low, double reach = 0.7) {
  FlightScenario f = ShippedFlightScenario().flight;
  f.duration_s = seconds;
  f.excitation.start_s = 0.5;
  f.excitation.period_s = 5.0;
  f.excitation.min_hz = 0.2;
  const double h0 = low ? 0.3 : 1.5, h1 = low ? 0.6 : 1.8;
  // Near the floor half the flight at each height, so that the height, not
  // only the thrust scale, tells the ground effect.
  f.waypoints = {Waypoint{0, 0, 0, h0, 0},
                 Waypoint{low ? seconds / 2 : 1.0, 0.8 * reach, 0.6 * reach, h1, 0.2}};
  return f;
}

DiscoveryOptions Options() {
  DiscoveryOptions o;
  o.alpha = 0.01;
  o.fit.num_threads = 2;
  o.fit.noise_relaxations = 1;
  // The declared model's fit to a log with an undeclared effect crawls along
  // its misfit for tens of iterations (measured: 60 for the last 0.2 % of the
  // cost with an undeclared wind); the candidates' tests project the fitted
  // directions out, so they do not need those iterations, and a refit with
  // the right effect has its noise-relaxation solve to finish in.
  o.fit.max_iterations = 15;
  // COAXID_TEST_PROGRESS=1 prints the loop's and the fits' progress (these runs take seconds).
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

// Fast transits: waypoints 5-7 m apart every 7-8 s with climbs and descents,
// a stiffer position loop allowed 0.25 rad of tilt (up to ~2.4 m/s), and a
// stronger collective excitation: the speeds and rotor speeds vary enough for
// velocity-dependent loads to differ in shape from the body drag of eq. 24.
FlightScenario TransitFlight(double seconds) {
  FlightScenario f = ShortFlight(seconds, false);
  f.gains.pos_kp = 1.0;
  f.gains.pos_kd = 1.2;
  f.gains.max_tilt = 0.25;
  f.excitation.amplitude["omega1"] = f.excitation.amplitude["omega2"] = 8.0;
  f.excitation.period_s = 10.0;
  const double corners[][3] = {{4, 3, 3.0}, {-3, -3, 1.0}, {4, -3, 2.5}, {0, 2, 1.5}, {-4, 3, 3.0},
                               {3, -3, 1.0}, {-4, -3, 2.5}, {0, 0, 1.5}};
  f.waypoints = {Waypoint{0, 0, 0, 1.5, 0}};
  double t = 2;
  for (const auto& c : corners) {
    if (t >= seconds) break;
    f.waypoints.push_back(Waypoint{t, c[0], c[1], c[2], 0});
    t += 7.5;
  }
  return f;
}

FlightRun DiscoverIn(const Effects& effects, const FlightScenario& f, uint64_t seed,
                     const DiscoveryOptions& options = Options()) {
  FlightRun run;
  run.truth = Truth(effects);
  const Log estimation = SimulateFlight(run.truth, f, seed);
  const Log validation = SimulateFlight(run.truth, f, seed + 500);
  // A short balance log fixes the moment and force scales a flight alone
  // leaves free (output_error.h: flight logs fix only ratios such as J_r / Ixx).
  BalanceScenario b;
  b.hold_s = 0.5;
  b.rate_hz = 50;
  const Log balance = SimulateBalance(run.truth, b, seed + 1000);
  run.result = Discover(Nominal(), {MakeEstimationLog(estimation), MakeEstimationLog(balance)},
                        {MakeEstimationLog(validation)}, options);
  return run;
}

FlightRun DiscoverInFlight(const Effects& effects, bool low, uint64_t seed, double reach = 0.7,
                           double seconds = 10) {
  return DiscoverIn(effects, ShortFlight(seconds, low, reach), seed);
}

// The model's part of a channel's held-out error: rms^2 = model error^2 +
// sensor noise^2 (independent), the noise std being the scenario's, over the
// square root of the rows the loop averaged into one (fit_rate.h).
double ModelError(const DiscoveryResult& r, const ModelSnapshot& s, const std::string& channel) {
  const double rms = s.validation.at(channel).rms;
  const double noise = ShippedFlightScenario().flight.noise_std.at(channel) /
                       std::sqrt(r.validation.at(0).rows_averaged);
  return std::sqrt(std::max(0.0, rms * rms - noise * noise));
}

double MeanModelError(const DiscoveryResult& r, const ModelSnapshot& s,
                      const std::vector<std::string>& channels) {
  double sum = 0;
  for (const std::string& c : channels) sum += ModelError(r, s, c);
  return sum / channels.size();
}

struct EffectCase {
  std::string effect;
  std::map<std::string, double> truth;  // its parameters in the truth
  bool low;                             // flown near the floor
  double reach;                         // distance to the waypoint [m]
  std::vector<std::string> channels;    // the channels it drives
  uint64_t seed;
};

std::ostream& operator<<(std::ostream& o, const EffectCase& c) { return o << c.effect; }

class DiscoverFlightEffect : public testing::TestWithParam<EffectCase> {};

TEST_P(DiscoverFlightEffect, FindsItAndOnlyIt) {
  const EffectCase& c = GetParam();
  std::map<std::string, ParameterOverride> overrides;
  for (const auto& [name, v] : c.truth) overrides[name] = Value(v);
  const FlightRun run = DiscoverInFlight({{c.effect, overrides}}, c.low, c.seed, c.reach);
  const DiscoveryResult& r = run.result;
  ASSERT_EQ(r.added, std::vector<std::string>{c.effect});
  // "Clearly": the model's part of the held-out error of the channels it
  // drives (the rms without the sensor noise, which no model removes) falls
  // by half or more on average.
  const double before = MeanModelError(r, r.baseline, c.channels);
  const double after = MeanModelError(r, r.final, c.channels);
  EXPECT_LT(after, 0.5 * before) << "held-out model error " << before << " -> " << after;
  for (const auto& [name, v] : c.truth) ExpectWithinThreeStd(r, run.truth, c.effect + "." + name);
  // The held-out share is computed only for refits that pass every gate on
  // the estimation data; an added effect passed the held-out gate too, where
  // the held-out flight can judge it (NaN: most of its gain lay in the
  // balance's channels, as the wind's does: its refit lets Cx and Cy come
  // back to what the balance's X and Y say).
  for (const CandidateScore& s : r.candidates) {
    if (s.confirmed && !std::isnan(s.share_of_excess_held_out)) {
      EXPECT_GE(s.share_of_excess_held_out, Options().min_share_of_excess) << s.effect;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Library, DiscoverFlightEffect,
    // Strengths: clearly visible, yet small beside the excitation (a bias
    // or offset as large as the excitation makes the declared fit crawl).
    testing::Values(
        EffectCase{"gyroscopic", {{"J_r", 3e-4}}, false, 0.7, {"p", "q"}, 61},
        EffectCase{"rotor_damping", {{"k_pq", 2e-3}}, false, 0.7, {"p", "q"}, 62},
        EffectCase{"ground_effect", {{"k_ge", 1.0}}, true, 0.7, {"w", "az"}, 63},
        EffectCase{"swashplate_bias", {{"b_x", 3e-3}, {"b_y", -2e-3}}, false, 0.7,
                   {"p", "q", "phi", "theta"}, 65},
        EffectCase{"cg_offset", {{"x_g", 1e-3}, {"y_g", -0.7e-3}}, false, 0.7,
                   {"p", "q", "phi", "theta"}, 67},
        EffectCase{"wind", {{"wn", 0.6}, {"we", -0.5}, {"wd", 0.0}}, false, 2.5,
                   {"u", "v", "ax", "ay"}, 66},
        // Measurement effects (issue 14): at their library typical strength,
        // 1-2 x the sensors' noise std.
        EffectCase{"gyro_bias", {{"b_p", 0.02}, {"b_q", -0.015}, {"b_r", 0.01}}, false, 0.7,
                   {"p", "q", "r"}, 68},
        EffectCase{"accel_bias", {{"b_ax", 0.15}, {"b_ay", -0.1}, {"b_az", 0.2}}, false, 0.7,
                   {"ax", "ay", "az"}, 69},
        // The actuator effect (issue 14): servos 40 ms late.
        EffectCase{"servo_lag", {{"T_s", 0.04}}, false, 0.7, {"p", "q", "phi", "theta"}, 70},
        // Rotors 80 and 60 ms behind their speed commands.
        EffectCase{"motor_lag", {{"T_m1", 0.08}, {"T_m2", 0.06}}, false, 0.7, {"w", "az", "r"},
                   72}),
    [](const testing::TestParamInfo<EffectCase>& info) { return info.param.effect; });

// The same effects added and the same final estimates (to 1e-9 of each).
void ExpectTheSameAnswer(const DiscoveryResult& cut, const DiscoveryResult& full) {
  EXPECT_EQ(cut.added, full.added);
  const ParameterSet& a = cut.final.result.parameters;
  const ParameterSet& b = full.final.result.parameters;
  for (const std::string& name : b.FreeNames()) {
    EXPECT_NEAR(a.Value(name), b.Value(name), 1e-9 * std::fabs(b.Value(name))) << name;
  }
}

// A qualifying refit that removes nearly all of the excess error over all
// channels decides its round: the refits ranked below it are not run
// (decisive_share_of_all_excess). Leaving them out changes nothing the loop
// decides: the same effects and the same final estimates as with every
// shortlisted refit run to its end.
TEST(DiscoverFlight, ARefitThatDecidesItsRoundChangesNothingByLeavingOutTheRest) {
  const Effects effects = {{"cg_offset", {{"x_g", Value(1e-3)}, {"y_g", Value(-0.7e-3)}}}};
  const FlightScenario f = ShortFlight(10, /*low=*/false);
  DiscoveryOptions every_refit = Options();
  every_refit.decisive_share_of_all_excess = INFINITY;
  const DiscoveryResult cut = DiscoverIn(effects, f, 67).result;
  const DiscoveryResult full = DiscoverIn(effects, f, 67, every_refit).result;
  int not_judged = 0;
  for (const CandidateScore& s : cut.candidates) {
    if (s.why_not_confirmed.rfind("not judged", 0) != 0) continue;
    ++not_judged;
    EXPECT_FALSE(s.refitted) << s.effect;
    // As scored: nothing of a refit (its estimates, its Wald test).
    EXPECT_EQ(s.parameters.size(), 0) << s.effect;
    EXPECT_EQ(s.wald_p_value, 1) << s.effect;
    EXPECT_TRUE(s.refit_starts.empty()) << s.effect;
  }
  ASSERT_GT(not_judged, 0) << "no refit decided its round: this case tests nothing";
  ExpectTheSameAnswer(cut, full);
}

// A shortlisted candidate whose channels hold less excess error than a
// refit must remove from (min_channels_excess) is not refitted: nothing its
// refit could show would be added, hold back another or start a pair.
// Leaving those refits out changes nothing the loop decides: the same
// effects and final estimates as with them run.
// (Seed 81, no undeclared effect: gyroscopic passes its score test, its
// channels at 0.01 noise variances of excess.)
TEST(DiscoverFlight, ACandidateWithoutExcessInItsChannelsIsNotRefittedAndChangesNothing) {
  const FlightScenario f = ShortFlight(8, /*low=*/false);
  DiscoveryOptions every_refit = Options();
  every_refit.refit_without_excess = true;
  const DiscoveryResult cut = DiscoverIn({}, f, 81).result;
  const DiscoveryResult full = DiscoverIn({}, f, 81, every_refit).result;
  int left_out = 0;
  for (const CandidateScore& s : cut.candidates) {
    if (s.why_not_confirmed.rfind("not refitted: its channels hold almost no excess", 0) != 0) {
      continue;
    }
    ++left_out;
    EXPECT_FALSE(s.refitted) << s.effect;
    EXPECT_LT(s.channels_excess, Options().min_channels_excess) << s.effect;
    EXPECT_TRUE(s.refit_starts.empty()) << s.effect;
    // The same round's candidate, refitted: rejected.
    const auto same = std::find_if(full.candidates.begin(), full.candidates.end(),
                                   [&](const CandidateScore& x) {
                                     return x.round == s.round && x.effect == s.effect;
                                   });
    ASSERT_NE(same, full.candidates.end()) << s.effect;
    EXPECT_TRUE(same->refitted) << s.effect;
    EXPECT_FALSE(same->confirmed) << s.effect;
  }
  ASSERT_GT(left_out, 0) << "every shortlisted candidate had excess to remove: this case tests nothing";
  ExpectTheSameAnswer(cut, full);
}

// The loop's answer does not depend on its threads (OutputErrorOptions::
// num_threads is every core): on one thread and on three, the same effects,
// candidates' tests and final estimates, to the last bit.
TEST(DiscoverFlight, TheLoopIsTheSameOnOneThreadAndOnThree) {
  const Effects effects = {{"cg_offset", {{"x_g", Value(1e-3)}, {"y_g", Value(-0.7e-3)}}}};
  const FlightScenario f = ShortFlight(10, /*low=*/false);
  DiscoveryOptions one = Options(), three = Options();
  one.fit.num_threads = 1;
  three.fit.num_threads = 3;
  const DiscoveryResult a = DiscoverIn(effects, f, 67, one).result;
  const DiscoveryResult b = DiscoverIn(effects, f, 67, three).result;
  ASSERT_FALSE(a.added.empty()) << "nothing added: this case tests too little";
  EXPECT_EQ(a.added, b.added);
  ASSERT_EQ(a.candidates.size(), b.candidates.size());
  for (size_t k = 0; k < a.candidates.size(); ++k) {
    EXPECT_EQ(a.candidates[k].effect, b.candidates[k].effect);
    EXPECT_EQ(a.candidates[k].p_value, b.candidates[k].p_value) << a.candidates[k].effect;
    EXPECT_EQ(a.candidates[k].wald_p_value, b.candidates[k].wald_p_value)
        << a.candidates[k].effect;
  }
  const ParameterSet& x = a.final.result.parameters;
  const ParameterSet& y = b.final.result.parameters;
  for (const std::string& name : x.FreeNames()) EXPECT_EQ(x.Value(name), y.Value(name)) << name;
}

TEST(DiscoverFlight, RotorDragIsTakenByTheBodyDragNotByAWrongEffect) {
  // Near hover the body drag of eq. 24, X = rho/2 S_c Cx V_ux V_tot, is
  // linear in u too (V_tot ~ V_prop), like the rotor drag -k_h (omega1 +
  // omega2) u at nearly constant rotor speeds: with Cx, Cy free the declared
  // model absorbs the rotor drag (and a balance, which does not move, cannot
  // show it). Measured with a 2.5 m transit and Cx, Cy held known, the
  // transit's drag looks like a wind as much as a rotor drag. So the
  // property tested is the honest one: nothing is added.
  const FlightRun run = DiscoverInFlight({{"rotor_drag", {{"k_h", Value(3e-4)}}}}, false, 64);
  EXPECT_TRUE(run.result.added.empty()) << "added " << run.result.added.front();
}

TEST(DiscoverFlight, RotorDragIsFoundInFastTransits) {
  // The experiment that separates them: fast transits with climbs (see
  // TransitFlight). Measured with the CLI on a 60 s log: rotor_drag passes
  // (Holm p 1.5e-3), wind does not (p 0.64), k_h = 5.99e-4 +- 3.3e-6 for
  // a truth of 6e-4.
  const double k_h = 6e-4;
  const FlightRun run = DiscoverIn({{"rotor_drag", {{"k_h", Value(k_h)}}}}, TransitFlight(40), 71);
  const DiscoveryResult& r = run.result;
  ASSERT_EQ(r.added, std::vector<std::string>{"rotor_drag"});
  const std::vector<std::string> channels = {"u", "v", "ax", "ay"};
  const double before = MeanModelError(r, r.baseline, channels);
  const double after = MeanModelError(r, r.final, channels);
  EXPECT_LT(after, 0.5 * before) << "held-out model error " << before << " -> " << after;
  ExpectWithinThreeStd(r, run.truth, "rotor_drag.k_h");
}

TEST(DiscoverFlight, TwoEffectsAreBothFound) {
  const FlightRun run = DiscoverInFlight(
      {{"gyroscopic", {{"J_r", Value(3e-4)}}}, {"wind", {{"wn", Value(0.6)}, {"we", Value(-0.5)}}}},
      false, 71, 2.5, 14);
  std::vector<std::string> added = run.result.added;
  std::sort(added.begin(), added.end());
  EXPECT_EQ(added, (std::vector<std::string>{"gyroscopic", "wind"}));
}

TEST(DiscoverFlight, ABarBesideASwashplateBiasAreBothFound) {
  // The library's typical bar and swashplate bias. Alone, the bar's refit
  // carries T_b to its bound (its slow tilt standing in for the bias); the
  // bias's refit removes 33 % of its channels' excess, most of it in the
  // balance's L and M, which the held-out flight cannot judge
  // (practical_significance.h), and is added in round 1, the bar in round 2.
  // (Until the held-out gate judged only where the gain lies, the held-out
  // flight rejected the bias and the pair was found by the paired refit,
  // paired_refit.h.)
  const FlightRun run = DiscoverInFlight(
      {{"stabilizer_bar", {{"T_b", Value(1.8)}, {"k_b", Value(0.6)}, {"d_u", Value(0.165)}}},
       {"swashplate_bias", {{"b_x", Value(0.015)}, {"b_y", Value(-0.01)}}}},
      false, 73, 0.7, 10);
  std::vector<std::string> added = run.result.added;
  std::sort(added.begin(), added.end());
  EXPECT_EQ(added, (std::vector<std::string>{"stabilizer_bar", "swashplate_bias"}));
  EXPECT_TRUE(run.result.removed.empty());
  for (const char* name : {"stabilizer_bar.T_b", "stabilizer_bar.k_b", "swashplate_bias.b_x",
                           "swashplate_bias.b_y"}) {
    ExpectWithinThreeStd(run.result, run.truth, name);
  }
}

// wake_interference beside a flight log: the short balance log separates it
// from sigma (a flight sees k_T omega1 omega2 as a part of sigma's loss), and
// its gain lies in the balance's channels, which the held-out flight does not
// measure: the held-out flight cannot judge it (a NaN share), and the
// estimation data decide. Measured before: its columns were called not
// separable (a squared sine below a fixed 1e-6 of their size), or its refit
// was rejected for removing "15 %" of the held-out flight's noise-level
// excess (docs/discover_confusion.md, thirty-third session).
TEST(DiscoverFlight, WakeInterferenceIsFoundBesideAFlightLog) {
  for (uint64_t seed : {74, 75}) {
    const FlightRun run = DiscoverInFlight(
        {{"wake_interference", {{"k_T", Value(5e-6)}, {"k_Q", Value(1e-7)}}}}, false, seed);
    ASSERT_EQ(run.result.added, std::vector<std::string>{"wake_interference"}) << "seed " << seed;
    ExpectWithinThreeStd(run.result, run.truth, "wake_interference.k_T");
    ExpectWithinThreeStd(run.result, run.truth, "wake_interference.k_Q");
    for (const CandidateScore& s : run.result.candidates) {
      if (s.confirmed) {
        EXPECT_TRUE(std::isnan(s.share_of_excess_held_out)) << s.effect;
      }
    }
  }
}

TEST(DiscoverFlight, NothingAddedWithoutAnUndeclaredEffect) {
  // Family-wise alpha = 0.01 per run: over 2 seeds a false alarm has
  // probability ~2 % if the test keeps its level (20 seeds measured by
  // bench/discover_false_alarm_bench, README).
  int false_alarms = 0;
  for (uint64_t seed = 81; seed < 83; ++seed) {
    const FlightRun run = DiscoverInFlight({}, false, seed, 0.7, 8);
    false_alarms += !run.result.added.empty();
  }
  EXPECT_EQ(false_alarms, 0);
}

TEST(DiscoverFlight, EffectOutsideTheLibraryIsReportedUnexplained) {
  // A yaw moment that follows the lateral swashplate angle, N += k delta_cx
  // (experiments/simulation/outside_library_loads.h), written into the
  // truth's double-valued model only: no library effect has that shape. At
  // k = 4 mN m/rad (the top of the confusion study's range) r's residual
  // stays structured.
  Scenario s = ShippedFlightScenario();
  s.truth_outside_library["yaw_from_swashplate"] = 4e-3;
  const Vehicle truth = MakeTruthVehicle(Nominal().config, s);
  const FlightScenario f = ShortFlight(8, false);
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
}

TEST(DiscoverFlight, SensorBiasOfTheScenarioIsFoundAsGyroBias) {
  // The yaw-rate gyro reads 0.05 rad/s high (5 x its noise), written through
  // the scenario's sensor model (FlightScenario::bias), not through the
  // library's gyro_bias: discover names it gyro_bias (issue 14) and only it,
  // with b_r within 3 std of 0.05 and b_p, b_q of 0.
  const Vehicle truth = Truth({});
  FlightScenario f = ShortFlight(8, false);
  f.bias["r"] = 0.05;
  auto log = [&](uint64_t seed) { return MakeEstimationLog(SimulateFlight(truth, f, seed)); };
  const DiscoveryResult r = Discover(Nominal(), {log(93)}, {log(94)}, Options());
  ASSERT_EQ(r.added, std::vector<std::string>{"gyro_bias"});
  ExpectGyroBiasWithinThreeStd(r, truth, 0.05);
}

}  // namespace
}  // namespace coaxid
