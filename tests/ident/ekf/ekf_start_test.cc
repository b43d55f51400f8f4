// The EKF start (ident/ekf/ekf_start.h) lets the output-error fit skip its
// coarse stage: from it, one solve at 1 s segments lands in the minimum the
// nominal start's coarse-to-fine schedule finds, on truth vehicles and noise
// seeds the start was not tuned on.
#include <cmath>

#include <gtest/gtest.h>

#include "experiments/simulation/simulate_experiment.h"
#include "ident/ekf/ekf_start.h"
#include "ident/output_error/output_error.h"
#include "tests/random_truth.h"
#include "tests/shipped_flight.h"

namespace coaxid {
namespace {

TEST(EkfStart, OneFineSolveLandsWhereCoarseToFineDoes) {
  const Vehicle nominal = ShippedVehicle();
  const FlightScenario flight = ExcitedShippedFlight(10);
  for (uint64_t seed : {61, 62, 63}) {
    const Vehicle truth = RandomTruth(nominal, seed);
    const std::vector<EstimationLog> logs = {
        MakeEstimationLog(SimulateFlight(truth, flight, seed + 1000))};

    const OutputErrorResult coarse_to_fine = FitOutputError(nominal, logs, OutputErrorOptions{});
    ASSERT_TRUE(coarse_to_fine.usable) << coarse_to_fine.why_not_usable;
    const EkfStart ekf = StartFromEkfPass(nominal, logs);
    ASSERT_TRUE(ekf.usable) << ekf.note;
    Vehicle start = nominal;
    start.parameters = ekf.parameters;
    OutputErrorOptions fine_only;
    fine_only.segment_schedule_s = {1.0};
    const OutputErrorResult from_ekf = FitOutputError(start, logs, fine_only);
    ASSERT_TRUE(from_ekf.usable) << from_ekf.why_not_usable;

    ASSERT_EQ(from_ekf.ratios.size(), coarse_to_fine.ratios.size());
    for (size_t k = 0; k < from_ekf.ratios.size(); ++k) {
      const ScaleFreeRatio& a = from_ekf.ratios[k];
      const ScaleFreeRatio& b = coarse_to_fine.ratios[k];
      // One minimum: the two end points differ by the solver's tolerance
      // (a relative cost change of 1e-7), far below 0.1 std.
      EXPECT_LT(std::fabs(a.value - b.value), 0.1 * b.std)
          << "seed " << seed << " " << a.name << ": " << a.value << " vs " << b.value << " +- "
          << b.std;
      // And the right one: 3 std (18 checks; a false alarm ~5 %).
      EXPECT_LT(std::fabs(a.value - a.Evaluate(truth.parameters)), 3 * a.std)
          << "seed " << seed << " " << a.name;
    }
  }
}

}  // namespace
}  // namespace coaxid
