#include "experiments/studies/share_threshold.h"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace coaxid {
namespace {

nlohmann::json Refit(const std::string& effect, int round, bool significant, double share,
                     nlohmann::json share_held_out, double removed_all) {
  return {{"round", round},        {"effect", effect},
          {"significant", significant}, {"confirmed", false},
          {"share", share},        {"share_held_out", share_held_out},
          {"excess_removed_all_channels", removed_all}};
}

nlohmann::json RunRecord(const std::string& truth, const std::string& truth_class,
                   const std::vector<nlohmann::json>& refits) {
  return {{"draw", {{"truth", truth}, {"truth_class", truth_class}, {"balance", false}}},
          {"methods", {{"discover", {{"ok", true}, {"added", nlohmann::json::array()},
                                     {"refits", refits}}}}}};
}

const nlohmann::json& Row(const nlohmann::json& s, double threshold) {
  for (const nlohmann::json& r : s["thresholds"]) {
    if (std::abs(r["threshold"].get<double>() - threshold) < 1e-12) return r;
  }
  ADD_FAILURE() << "no row for " << threshold;
  return s;
}

// Three runs whose decisions are worked out by hand at 0.1, 0.3 and 0.9.
TEST(ShareThreshold, ReplaysRoundOneDecisionsAtEachThreshold) {
  const std::vector<nlohmann::json> records = {
      // Wind in the truth: wind removes 95 % (80 % held out), cg_offset 12 %
      // (held out not computed) but more excess over all channels.
      RunRecord("wind", "single",
          {Refit("wind", 1, true, 0.95, 0.80, 10.0), Refit("cg_offset", 1, true, 0.12, nullptr, 20.0),
           Refit("gyroscopic", 2, true, 0.99, 0.99, 50.0)}),  // round 2: not replayed
      // No effect: a significant false refit removing 20 %.
      RunRecord("none", "none", {Refit("wind", 1, true, 0.20, nullptr, 1.0)}),
      // Ground effect held out at 25 %: qualifies below 0.25 only; rotor_drag
      // not significant (never qualifies).
      RunRecord("ground_effect", "single",
          {Refit("ground_effect", 1, true, 0.60, 0.25, 5.0),
           Refit("rotor_drag", 1, false, 0.90, 0.90, 9.0)}),
      {{"key", "failed"}, {"methods", {{"discover", {{"ok", false}}}}}}};
  const nlohmann::json s = ShareThresholdSummary(records);
  EXPECT_EQ(s["runs"], 3);
  EXPECT_EQ(s["true_significant"], 2);   // wind, ground_effect
  EXPECT_EQ(s["false_significant"], 2);  // cg_offset, wind in "none"
  const nlohmann::json& low = Row(s, 0.1);
  EXPECT_EQ(low["true_qualify"], 2);
  EXPECT_EQ(low["false_qualify"], 2);
  EXPECT_EQ(low["wrong_choice"], 2);  // cg_offset over wind; wind in "none"
  EXPECT_EQ(low["true_lost"], 0);
  const nlohmann::json& mid = Row(s, 0.3);
  EXPECT_EQ(mid["true_qualify"], 1);  // wind; ground effect's 25 % held out fails
  EXPECT_EQ(mid["false_qualify"], 0);
  EXPECT_EQ(mid["wrong_choice"], 0);
  EXPECT_EQ(mid["true_lost"], 1);
  const nlohmann::json& high = Row(s, 0.9);
  EXPECT_EQ(high["true_qualify"], 0);  // wind's held-out 80 % fails
  EXPECT_EQ(high["true_lost"], 2);
  const std::string md = ShareThresholdMarkdown(s);
  EXPECT_NE(md.find("| 0.30 | 1 | 0 | 0 | 1 |"), std::string::npos) << md;
}

}  // namespace
}  // namespace coaxid
