// Two effects added as a pair when one of them alone ends at its own bound
// (ident/discover/paired_refit.h), end to end through the CLI, on two draws
// of a CG offset beside a stabilizer bar, flight with the balance log, that
// the judged sets missed:
//  - seed 11966 of configs/studies/discover_confusion.yaml (2026-12-06),
//    hover: the declared fit leaves Ixx and Iyy at their upper bound; alone,
//    the bar's refit carries T_b and d_u to their bounds and removes 20 % of
//    its channels' excess at the fit rate (24 % fitting every row), the CG
//    offset's removes none, and nothing was added (phi, theta, p, q reported
//    unexplained);
//  - seed 11031 of configs/studies/discover_controllers.yaml (its judged set
//    of 2026-12-06, thirtieth session), low flight, its own controller: the
//    same, the bar removing 14 % (fitting every row its refit is not
//    significant).
// Refitted with the bar in the model (DiscoveryOptions::min_share_to_pair,
// 0.1), the CG offset qualified and the pair removed all of the excess (both
// failed with min_share_to_pair at the practical threshold, 0.3, 11031 also
// at 0.15). Since the held-out flight judges a refit only where its gain lies
// in channels the flight measures (practical_significance.h), both are found
// without the pair: the CG offset's refit alone removes 98 % of its channels'
// excess, nearly all of it in the balance's L and M, and is added in round 1,
// the bar in round 2. The test keeps both draws: both effects, within 3 std.
// (A pair beside a bar at its bound still happens: seed 13276, flight only,
// low, in the judged set of 2026-12-07; 50-90 s, too long for a test.)
//
// A bar the round never refitted because wind qualified before it, though
// the fit with wind still lost the rates (shortlist.h), on seed 22946 of
// the controllers' spec drawn at 60 s, as bench/discover_speed.sh draws it.
//
// And a pair started from a refit that is not significant but removes far
// more than the one that qualifies (ident/discover/round_choice.h), on seed
// 21253 of the confusion spec (bench/discover_speed.sh, 2026-12-06): wind
// beside a ground effect, low flight, flight only.
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/discover_on_a_draw.h"

namespace coaxid {
namespace {

class DiscoverPairCli : public DiscoverOnADraw {
 protected:
  // Both effects added, their five parameters within 3 std of the draw's
  // truth.
  void ExpectThePair(const StudySpec& spec, uint64_t seed) {
    const RandomDraw draw = DrawRun(spec, seed);
    ASSERT_EQ(draw.truth_label, "cg_offset+stabilizer_bar");
    const nlohmann::json j = Discover(spec, draw, std::to_string(seed) + "_");
    ASSERT_FALSE(j.is_null());
    ASSERT_EQ(SortedAdded(j), (std::vector<std::string>{"cg_offset", "stabilizer_bar"}))
        << j["added"].dump();
    EXPECT_DOUBLE_EQ(j["settings"]["min_share_to_pair"].get<double>(), 0.1);
    EXPECT_TRUE(j["removed"].empty()) << j["removed"].dump();
    // Every parameter of both effects within 3 of its reported std of the truth
    // (the flight and the balance fix the scale: d is estimated).
    std::map<std::string, double> truth;
    for (const auto& [effect, overrides] : draw.scenarios[0].truth_effects) {
      for (const auto& [name, o] : overrides) {
        if (o.value) truth[effect + "." + name] = *o.value;
      }
    }
    const nlohmann::json& final_parameters = j["final"]["parameters"];
    for (const char* name : {"cg_offset.x_g", "cg_offset.y_g", "stabilizer_bar.T_b",
                             "stabilizer_bar.k_b", "stabilizer_bar.d_u"}) {
      ASSERT_TRUE(truth.count(name)) << name;
      const double value = final_parameters[name]["value"].get<double>();
      const double std = final_parameters[name]["std"].get<double>();
      EXPECT_LE(std::abs(value - truth[name]), 3 * std)
          << name << " = " << value << " +- " << std << ", truth " << truth[name];
    }
  }
};

TEST_F(DiscoverPairCli, ACgOffsetBesideABarIsFoundWithIt) {
  const StudySpec confusion = ConfusionSpec(), controllers = ControllersSpec();
  for (const auto& [spec, seed] :
       {std::pair(&confusion, 11966u), std::pair(&controllers, 11031u)}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    ExpectThePair(*spec, seed);
  }
}

// Seed 22946 of the controllers' spec, every flight 60 s (bench/
// discover_speed.sh, 2026-12-07): a CG offset beside a stabilizer bar (T_b
// 1.9 s), flight only, hover. The declared fit leaves Ixx and Iyy at their
// upper bound and predicts p, q and ax no better than their mean. Before
// the change wind, blind at the bounds, qualified in round 1 on the
// translational channels, the bar waited for the slots and was never
// refitted; wind was added and p, q stayed unexplained (38.6 s). Now the
// bar is refitted, since wind's refit still predicts p and q no better than
// their mean: alone it takes T_b to its bound and removes 91 % of the
// excess over all channels, holds wind back, and is added with the CG
// offset as a pair (12-15 s).
// The bar's refit is sensitive to rounding: in the sanitizer build (-O1)
// it ends removing 46 % of all channels' excess, not 91 %, wind is added in
// round 1, the pair in round 2, and wind is taken out as made redundant by
// the CG offset. So the test asks what the change does on any build (the
// bar refitted in round 1 though wind qualified) and where the loop ends
// (the pair; wind, if added on the way, taken out), not which of the two
// paths it took. Flight only, the scale is held (d at its config value):
// the bar's T_b and k_b and the scale-free ratios of the CG offset and the
// hub height are compared with the truth, within 3 of their reported std
// (the largest measured: y_g / Ixx, 2.8).
TEST_F(DiscoverPairCli, AQualifierThatStillLosesTheRatesDoesNotStopTheBarsRefit) {
  StudySpec spec = ControllersSpec();
  spec.randomise.duration_s = {60, 60};
  const RandomDraw draw = DrawRun(spec, 22946);
  ASSERT_EQ(draw.truth_label, "cg_offset+stabilizer_bar");
  ASSERT_EQ(draw.scenarios.size(), 1u);  // flight only
  const nlohmann::json j = Discover(spec, draw);
  ASSERT_FALSE(j.is_null());
  ASSERT_EQ(SortedAdded(j), (std::vector<std::string>{"cg_offset", "stabilizer_bar"}))
      << j["added"].dump();
  for (const nlohmann::json& r : j["removed"]) {
    EXPECT_EQ(r["effect"], "wind") << j["removed"].dump();
  }
  bool wind_qualified = false, bar_refitted = false;
  for (const nlohmann::json& c : j["candidates"]) {
    const bool paired = c.contains("beside") && !c["beside"].is_null();
    if (c.value("round", 0) != 1 || paired || !c.contains("refit") || c["refit"].is_null()) {
      continue;
    }
    wind_qualified |= c["effect"] == "wind" && c["refit"].value("share_of_excess_removed", 0.0) >=
                                                   j["settings"]["min_share_of_excess"].get<double>();
    bar_refitted |= c["effect"] == "stabilizer_bar";
  }
  EXPECT_TRUE(wind_qualified) << "the draw no longer shows the case this test is for";
  EXPECT_TRUE(bar_refitted) << "wind qualified and the bar, waiting behind it, was not refitted";
  std::map<std::string, double> truth;
  for (const auto& [effect, overrides] : draw.scenarios[0].truth_effects) {
    for (const auto& [name, o] : overrides) {
      if (o.value) truth[effect + "." + name] = *o.value;
    }
  }
  const double Ixx = draw.description["truth_parameters"]["Ixx"].get<double>();
  const std::map<std::string, double> expected = {
      {"stabilizer_bar.T_b", truth.at("stabilizer_bar.T_b")},
      {"stabilizer_bar.k_b", truth.at("stabilizer_bar.k_b")},
      {"cg_offset.x_g/Ixx", truth.at("cg_offset.x_g") / Ixx},
      {"cg_offset.y_g/Ixx", truth.at("cg_offset.y_g") / Ixx},
      {"stabilizer_bar.d_u/Ixx", truth.at("stabilizer_bar.d_u") / Ixx}};
  for (const auto& [name, value_of_truth] : expected) {
    const nlohmann::json& estimate = j["final"][name.find('/') == std::string::npos
                                                    ? "parameters"
                                                    : "ratios"][name];
    const double value = estimate["value"].get<double>();
    const double std = estimate["std"].get<double>();
    EXPECT_LE(std::abs(value - value_of_truth), 3 * std)
        << name << " = " << value << " +- " << std << ", truth " << value_of_truth;
  }
}

// Seed 21253, as measured before the change: the declared fit leaves Cx at
// 0 and Cz at 5; in round 1 wind's refit removes 96 % of the excess over all
// channels but is not significant (cluster-robust Wald p = 0.025 against
// 0.002: the missing ground effect's structured residual inflates the robust
// variance), the ground effect qualifies (1 %) and so does accel_bias (3 %),
// which was added as a stand-in for the wind's drag, refitted against for
// two rounds and removed in round 3 (34 s). Now wind holds accel_bias back,
// is refitted beside the ground effect and the pair is added in round 1;
// nothing is ever removed. Both effects' parameters within 3 std of the
// truth (wd: not identifiable here, within 0.5 m/s of the truth's 0). The
// 59 s log is searched whole (--search_window_s=0), as measured: searched on
// its first 20 s (the default since session 38), the window adds wind in
// round 1 and the ground effect in round 2, no pair needed.
TEST_F(DiscoverPairCli, WindThatIsNotSignificantAloneHoldsBackAStandInAndIsAddedAsAPair) {
  RandomDraw draw;
  const nlohmann::json j =
      DiscoverFlightOnly(21253, "ground_effect+wind", &draw, "--search_window_s=0");
  ASSERT_FALSE(j.is_null());
  ASSERT_EQ(SortedAdded(j), (std::vector<std::string>{"ground_effect", "wind"}))
      << j["added"].dump();
  EXPECT_TRUE(j["removed"].empty()) << j["removed"].dump();
  bool paired = false, stand_in_held_back = false;
  for (const nlohmann::json& c : j["candidates"]) {
    paired |= c["effect"] == "wind" && c.value("added_with", nlohmann::json()) == "ground_effect";
    stand_in_held_back |= c["effect"] == "accel_bias" && c.value("round", 0) == 1 &&
                          !c.contains("beside") && c.contains("refit") &&
                          c["refit"].value("why_not_confirmed", std::string())
                                  .find("wind 96 % though not significant") != std::string::npos;
  }
  EXPECT_TRUE(paired) << "found, but not by the paired refit this test is for";
  EXPECT_TRUE(stand_in_held_back);
  std::map<std::string, double> truth;
  for (const auto& [effect, overrides] : draw.scenarios[0].truth_effects) {
    for (const auto& [name, o] : overrides) {
      if (o.value) truth[effect + "." + name] = *o.value;
    }
  }
  const nlohmann::json& final_parameters = j["final"]["parameters"];
  for (const char* name : {"ground_effect.k_ge", "wind.we", "wind.wn"}) {
    ASSERT_TRUE(truth.count(name)) << name;
    const double value = final_parameters[name]["value"].get<double>();
    const double std = final_parameters[name]["std"].get<double>();
    EXPECT_LE(std::abs(value - truth[name]), 3 * std)
        << name << " = " << value << " +- " << std << ", truth " << truth[name];
  }
  EXPECT_LE(std::abs(final_parameters["wind.wd"]["value"].get<double>() - truth["wind.wd"]), 0.5);
}

}  // namespace
}  // namespace coaxid
