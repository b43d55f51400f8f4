// Effects.md step 7 end to end: a declared fit that leaves a parameter far
// outside its physical range is a symptom, reported in discovery.json with
// that range, and the candidates' refits restart it at its config value.
// Seed 9419 of configs/studies/discover_confusion.yaml (looked at when the
// rule was written, 2026-11-28): an undeclared stabilizer bar, flight with
// the balance log. The declared fit leaves Iyy at its upper bound and Ixx
// inside its bounds at 4.4 x m r^2, the most a body of the vehicle's mass
// and size can have; with only the bound restarted, the bar's refit ended
// above the current fit and nothing was added (0 of 1 found). With Ixx
// restarted too, the bar is added.
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/discover_on_a_draw.h"

namespace coaxid {
namespace {

using DiscoverSymptomCli = DiscoverOnADraw;

TEST_F(DiscoverSymptomCli, AnInertiaFarAboveItsPhysicalRangeIsRestartedAndTheBarFound) {
  StudySpec spec = ConfusionSpec();
  // The truth as drawn then: its Ixx, Iyy, Izz break the triangle inequality
  // (rigid-body draws give this seed other inertias since 2026-12-01).
  spec.randomise.rigid_body_inertias = false;
  const RandomDraw draw = DrawRun(spec, 9419);
  ASSERT_EQ(draw.truth_label, "stabilizer_bar");
  const nlohmann::json j = Discover(spec, draw);
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j["added"], nlohmann::json::array({"stabilizer_bar"}));
  // Ixx inside its bounds, far above m r^2: reported as such, with the range.
  bool ixx_far_above = false;
  for (const nlohmann::json& s : j["symptoms"]) {
    if (s["parameter"] != "Ixx") continue;
    ASSERT_FALSE(s["physical_range"].is_null()) << s.dump(2);
    ixx_far_above = s["value"].get<double>() > 2 * s["physical_range"][1].get<double>() &&
                    Contains(s["text"].get<std::string>(), "far outside its physical range");
  }
  EXPECT_TRUE(ixx_far_above) << j["symptoms"].dump(2);
}

}  // namespace
}  // namespace coaxid
