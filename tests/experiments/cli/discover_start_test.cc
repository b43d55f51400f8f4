// The declared fit's start, end to end through the CLI: a fit that fails
// from the EKF's starting values is fitted again from the config's (with
// the coarse-to-fine schedule), and the loop goes on. Seed 11183 of
// configs/studies/discover_controllers.yaml (its judged set of 2026-12-06,
// thirtieth session): a swashplate bias, flight with the balance log, its
// own controller. At the fit rate (pairs of rows averaged) the EKF pass over
// the first 20 s succeeds, and the output-error fit from its values fails at
// its first evaluation ("Residual and Jacobian evaluation failed"): discover
// exited 1. From the config's values the bias is found.
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/discover_on_a_draw.h"

namespace coaxid {
namespace {

using DiscoverStartCli = DiscoverOnADraw;

TEST_F(DiscoverStartCli, AFitThatFailsFromTheEkfStartStartsAgainFromTheConfig) {
  const StudySpec spec = ControllersSpec();
  const RandomDraw draw = DrawRun(spec, 11183);
  ASSERT_EQ(draw.truth_label, "swashplate_bias");
  const nlohmann::json j = Discover(spec, draw);
  ASSERT_FALSE(j.is_null());
  const std::string start = j["start"].get<std::string>();
  EXPECT_TRUE(Contains(start, "one EKF pass") &&
              Contains(start, "its fit failed: starting values from the config"))
      << start;
  EXPECT_EQ(j["added"], nlohmann::json::array({"swashplate_bias"}));
}

}  // namespace
}  // namespace coaxid
