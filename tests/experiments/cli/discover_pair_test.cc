// Two effects added as a pair when one of them alone ends at its own bound
// (ident/discover/paired_refit.h), end to end through the CLI. Seed 11966 of
// configs/studies/discover_confusion.yaml (the one visible pair missed by the
// judged set of 2026-12-06): a CG offset beside a stabilizer bar, hover, flight
// with the balance log. The declared fit leaves Ixx and Iyy at their upper
// bound; alone, the bar's refit carries T_b to its 10 s bound and removes 24 %
// of its channels' excess, the CG offset's removes none, and nothing was
// added (phi, theta, p, q reported unexplained). Refitted with the bar in the
// model (DiscoveryOptions::min_share_to_pair, 0.2), the CG offset qualifies
// and the pair removes all of the excess. Fails with min_share_to_pair at the
// practical threshold (0.3), the rule before.
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/discover_on_a_draw.h"

namespace coaxid {
namespace {

using DiscoverPairCli = DiscoverOnADraw;

TEST_F(DiscoverPairCli, ACgOffsetBesideABarAtItsBoundIsAddedWithIt) {
  const StudySpec spec = ConfusionSpec();
  const RandomDraw draw = DrawRun(spec, 11966);
  ASSERT_EQ(draw.truth_label, "cg_offset+stabilizer_bar");
  const nlohmann::json j = Discover(spec, draw);
  ASSERT_FALSE(j.is_null());
  std::vector<std::string> added = j["added"].get<std::vector<std::string>>();
  std::sort(added.begin(), added.end());
  ASSERT_EQ(added, (std::vector<std::string>{"cg_offset", "stabilizer_bar"})) << j["added"].dump();
  EXPECT_DOUBLE_EQ(j["settings"]["min_share_to_pair"].get<double>(), 0.2);
  bool paired = false;
  for (const nlohmann::json& c : j["candidates"]) {
    paired |= c["effect"] == "stabilizer_bar" && c.value("added_with", nlohmann::json()) == "cg_offset";
  }
  EXPECT_TRUE(paired) << "found, but not by the paired refit this test is for";
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

}  // namespace
}  // namespace coaxid
