// The EKF's smoother from checkpoints and recomputation (ident/ekf/pass.h)
// against the all-in-memory smoother (a block of every row: the RTS store of
// every step kept from the forward pass, nothing recomputed), on real EKF
// runs over the shipped flight logs.
//
// Tolerance: 1e-12 relative. The recomputed rows repeat the forward pass's
// arithmetic exactly (pass.cc checks the filter state at every block's end),
// and the backward recursion is the same per step, so the smoothed states
// should agree bit for bit; 1e-12 leaves room only for a reordering of sums.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/log.h"
#include "dynamics/vehicle.h"
#include "ident/ekf/ekf.h"
#include "ident/ekf/pass.h"
#include "ident/estimation_log.h"
#include "ident/noise_weights.h"

namespace coaxid {
namespace {

std::string Source(const std::string& rel) { return std::string(COAXID_SOURCE_DIR) + "/" + rel; }

// 15 s of the shipped flight and 10 s of the 3-2-1-1 flight, chained (a log boundary).
std::vector<EstimationLog> TwoLogs() {
  const Log a = ReadLog(Source("data/glmav/flight.csv"));
  const Log b = ReadLog(Source("data/glmav/flight_3211.csv"));
  return {MakeEstimationLog(a, 0, 3001), MakeEstimationLog(b, 0, 2001)};
}

EkfResult RunSmoothed(const std::vector<EstimationLog>& logs, long block_rows,
                      bool covariance_pass) {
  EkfOptions options;
  options.smoother = true;
  options.covariance_pass = covariance_pass;
  options.smoother_block_rows = block_rows;
  // The progress counts the recomputed rows too, and ends at its total.
  long done = 0, total = -1;
  options.progress = [&](long d, long t) {
    done = d;
    total = t;
  };
  const EkfResult r =
      RunEkf(LoadVehicle(Source("configs/glmav.yaml")), logs, NoiseFromData(logs), options);
  EXPECT_TRUE(r.usable) << r.failure;
  EXPECT_EQ(done, total);
  return r;
}

long Rows(const std::vector<EstimationLog>& logs) {
  long rows = 0;
  for (const EstimationLog& log : logs) rows += log.NumRows();
  return rows;
}

// Largest |a - b| / max(|b|, 1e-300) over the matrices' entries.
double RelativeDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  EXPECT_EQ(a.rows(), b.rows());
  EXPECT_EQ(a.cols(), b.cols());
  double worst = 0;
  for (int i = 0; i < a.rows(); ++i) {
    for (int j = 0; j < a.cols(); ++j) {
      const double scale = std::max(std::fabs(b(i, j)), 1e-300);
      worst = std::max(worst, std::fabs(a(i, j) - b(i, j)) / scale);
    }
  }
  return worst;
}

void ExpectSameSmoothedStates(const EkfResult& checkpointed, const EkfResult& in_memory) {
  ASSERT_EQ(checkpointed.logs.size(), in_memory.logs.size());
  for (size_t L = 0; L < in_memory.logs.size(); ++L) {
    const EkfLogHistory& c = checkpointed.logs[L];
    const EkfLogHistory& m = in_memory.logs[L];
    ASSERT_TRUE(m.smoothed_states.allFinite());
    ASSERT_TRUE(c.smoothed_states.allFinite());
    EXPECT_LE(RelativeDifference(c.smoothed_states, m.smoothed_states), 1e-12) << "log " << L;
    EXPECT_LE(RelativeDifference(c.smoothed_state_std, m.smoothed_state_std), 1e-12) << "log " << L;
    // The forward pass itself is untouched by the checkpoints.
    EXPECT_EQ(c.states, m.states);
  }
  EXPECT_EQ(checkpointed.estimate, in_memory.estimate);
  EXPECT_EQ(checkpointed.estimate_std, in_memory.estimate_std);
}

TEST(EkfCheckpointedSmootherTest, AutomaticBlockIsAboutSqrtOfTheRows) {
  EXPECT_EQ(SmootherBlockRows(5002, 0), 256);  // sqrt(5002) = 71: the floor of 256
  EXPECT_EQ(SmootherBlockRows(720000, 0), 849);
  EXPECT_EQ(SmootherBlockRows(720000, 1000), 1000);
}

TEST(EkfCheckpointedSmootherTest, MatchesInMemoryAcrossALogBoundary) {
  const std::vector<EstimationLog> logs = TwoLogs();
  const long rows = Rows(logs);
  ASSERT_EQ((rows - 1) % 997, 16);  // the last block is short, not a whole one
  const EkfResult in_memory = RunSmoothed(logs, rows, true);
  ExpectSameSmoothedStates(RunSmoothed(logs, 997, true), in_memory);
  // The automatic block (256 rows here): 20 blocks, the boundary inside one.
  ExpectSameSmoothedStates(RunSmoothed(logs, 0, true), in_memory);
  // A block boundary on the log boundary (step 3001 is row 0 of the second log).
  ExpectSameSmoothedStates(RunSmoothed(logs, 3001, true), in_memory);
}

TEST(EkfCheckpointedSmootherTest, MatchesInMemoryWhileTheParametersMove) {
  // Without the covariance pass the smoother runs in the estimation pass:
  // the recomputed rows must also repeat every parameter update.
  const std::vector<EstimationLog> logs = {TwoLogs()[0]};
  ExpectSameSmoothedStates(RunSmoothed(logs, 333, false), RunSmoothed(logs, Rows(logs), false));
}

}  // namespace
}  // namespace coaxid
