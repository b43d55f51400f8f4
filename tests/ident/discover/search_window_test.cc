// The loop's search on a window of a long flight log, confirmed on the whole
// log (DiscoveryOptions::search_window_s): what the window finds is fitted
// and judged again on the whole log, the baseline and the final model are
// fits of the whole log, and one more round on the whole log finds what the
// window cannot show.
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

DiscoveryOptions WindowOptions(double search_window_s) {
  DiscoveryOptions o;
  o.fit.num_threads = 2;
  o.fit.noise_relaxations = 1;
  o.fit.max_iterations = 15;  // as discovery_flight_test.cc
  o.search_window_s = search_window_s;
  if (getenv("COAXID_TEST_PROGRESS")) {
    o.progress = [](const std::string& l) { fprintf(stderr, "%s\n", l.c_str()); };
    o.fit.progress = o.progress;
  }
  return o;
}

// The shipped scenario's closed loop and multisine over `seconds`, hovering
// near (0, 0) at the heights of `waypoints` (t, height).
FlightScenario Hover(double seconds, const std::vector<std::pair<double, double>>& heights) {
  FlightScenario f = ShippedFlightScenario().flight;
  f.duration_s = seconds;
  f.excitation.start_s = 0.5;
  f.excitation.period_s = 5.0;
  f.excitation.min_hz = 0.2;
  f.waypoints.clear();
  for (const auto& [t, h] : heights) f.waypoints.push_back(Waypoint{t, 0.3, 0.2, h, 0.1});
  return f;
}

// Whether some round after the window's ran on the whole logs.
bool RoundOnTheWholeLogs(const DiscoveryResult& r) {
  return std::any_of(r.candidates.begin(), r.candidates.end(), [&](const CandidateScore& s) {
    return s.round > r.search_window.rounds;
  });
}

TEST(SearchWindow, WhatTheWindowFindsIsConfirmedAndEstimatedOnTheWholeLog) {
  // The yaw-rate gyro reads 0.05 rad/s high (5 x its noise) from the start:
  // the first 8 s show it, the whole 24 s estimate it.
  const Vehicle truth = Truth({});
  FlightScenario f = Hover(24, {{0, 1.5}, {1, 1.8}});
  f.bias["r"] = 0.05;
  auto log = [&](uint64_t seed) { return MakeEstimationLog(SimulateFlight(truth, f, seed)); };
  const EstimationLog estimation = log(193);
  const DiscoveryResult r = Discover(Nominal(), {estimation}, {log(194)}, WindowOptions(8));
  ASSERT_EQ(r.search_window.logs, std::vector<std::string>{estimation.source});
  EXPECT_TRUE(r.search_window.used) << r.search_window.note;
  EXPECT_EQ(r.search_window.added, std::vector<std::string>{"gyro_bias"});
  EXPECT_EQ(r.added, std::vector<std::string>{"gyro_bias"});
  EXPECT_TRUE(RoundOnTheWholeLogs(r));
  // The baseline and the final model are fits of the whole log (at the fit
  // rate), not of the window.
  const EstimationLog& whole = r.estimation.at(0).log;
  const int rows = whole.NumRows();
  EXPECT_GT(whole.inputs.times().back() - whole.inputs.times().front(), 23);
  EXPECT_EQ(r.baseline.result.predictions.at(0).rows(), rows);
  EXPECT_EQ(r.final.result.predictions.at(0).rows(), rows);
  ExpectGyroBiasWithinThreeStd(r, truth, 0.05);
}

TEST(SearchWindow, AGroundEffectAfterTheWindowIsFoundOnTheWholeLog) {
  // The first 10 s at 1.5-1.8 m, where the ground effect (k_ge = 1) is
  // nil; then down to 0.3-0.6 m for the remaining 20 s. The window (the
  // first 10 s) cannot show it; the round on the whole log must.
  const Vehicle truth = Truth({{"ground_effect", {{"k_ge", Value(1.0)}}}});
  const FlightScenario f = Hover(30, {{0, 1.5}, {1, 1.8}, {11, 0.3}, {20, 0.6}});
  auto log = [&](uint64_t seed) { return MakeEstimationLog(SimulateFlight(truth, f, seed)); };
  const DiscoveryResult r = Discover(Nominal(), {log(195)}, {log(196)}, WindowOptions(10));
  EXPECT_TRUE(r.search_window.used) << r.search_window.note;
  EXPECT_TRUE(r.search_window.added.empty());
  EXPECT_EQ(r.added, std::vector<std::string>{"ground_effect"});
  for (const CandidateScore& s : r.candidates) {
    if (s.confirmed) {
      EXPECT_GT(s.round, r.search_window.rounds) << s.effect << " confirmed on the window";
    }
  }
}

TEST(SearchWindow, ShortLogsAreSearchedWhole) {
  // A log no longer than twice the window is searched whole: no window is
  // reported, and the same answer as without windows.
  const Vehicle truth = Truth({});
  FlightScenario f = Hover(8, {{0, 1.5}, {1, 1.8}});
  f.bias["r"] = 0.05;
  auto log = [&](uint64_t seed) { return MakeEstimationLog(SimulateFlight(truth, f, seed)); };
  const DiscoveryResult with = Discover(Nominal(), {log(197)}, {log(198)}, WindowOptions(4));
  const DiscoveryResult without = Discover(Nominal(), {log(197)}, {log(198)}, WindowOptions(0));
  EXPECT_TRUE(with.search_window.logs.empty());
  EXPECT_EQ(with.added, without.added);
  EXPECT_EQ(with.final.result.final_cost, without.final.result.final_cost);
}

}  // namespace
}  // namespace coaxid
