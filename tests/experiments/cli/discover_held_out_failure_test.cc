// A model the loop only tries (a candidate's refit, the model without an
// added effect, the model at a first effect's bound) that cannot be
// simulated on the held-out flight is that model's failure, not the run's.
// Seed 13269 of configs/studies/discover_confusion.yaml (the judged set of
// 2026-12-07): a CG offset and gyroscopic moments, flight only. The CG
// offset is added in round 1 and gyroscopic moments in round 2; the check
// that the CG offset is still needed refits the model without it, and that
// model's held-out prediction cannot be integrated. Before, the whole run
// failed ("the model cannot be simulated on the held-out data", exit 1);
// now the CG offset is kept and both effects are found.
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/discover_on_a_draw.h"

namespace coaxid {
namespace {

class DiscoverHeldOutFailureCli : public DiscoverOnADraw {};

TEST_F(DiscoverHeldOutFailureCli, AModelWithoutAnEffectThatFailsOnTheHeldOutFlightKeepsIt) {
  RandomDraw draw;
  const nlohmann::json j = DiscoverFlightOnly(13269, "cg_offset+gyroscopic", &draw);
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(SortedAdded(j), (std::vector<std::string>{"cg_offset", "gyroscopic"}))
      << j["added"].dump();
  EXPECT_TRUE(j["removed"].empty()) << j["removed"].dump();
}

}  // namespace
}  // namespace coaxid
