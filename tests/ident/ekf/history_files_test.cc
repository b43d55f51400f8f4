// The streamed histories (ident/ekf/history_files.h) against the in-memory
// ones (EkfResult::logs and report.h's CSV writers): the same CSV bytes, the
// same thinned rows, the same states at chosen rows, the same convergence
// times; on a real EKF run over two shipped flight logs with a noise
// adaptation pass (two passes record innovations and parameters) and an
// innovation gate at 1e-2, so that the two passes reject different samples
// and the innovations of both are merged.
#include "ident/ekf/history_files.h"

#include <gtest/gtest.h>

#include <string>
#include <string_view>
#include <vector>

#include "core/log.h"
#include "dynamics/vehicle.h"
#include "ident/ekf/ekf.h"
#include "ident/ekf/report.h"
#include "ident/estimation_log.h"
#include "ident/noise_weights.h"

namespace coaxid {
namespace {

std::string Source(const std::string& rel) { return std::string(COAXID_SOURCE_DIR) + "/" + rel; }

std::string Text(const std::function<void(const EmitText&)>& table) {
  std::string text;
  table([&](std::string_view piece) { text += piece; });
  return text;
}

TEST(EkfHistoryFilesTest, WritesWhatTheInMemoryHistoryWrites) {
  const std::vector<EstimationLog> logs = {
      MakeEstimationLog(ReadLog(Source("data/glmav/flight.csv")), 0, 4001),
      MakeEstimationLog(ReadLog(Source("data/glmav/flight_3211.csv")), 0, 2001)};
  const Vehicle vehicle = LoadVehicle(Source("configs/glmav.yaml"));
  EkfOptions options;
  options.smoother = true;
  options.noise_adaptations = 1;
  options.gate_probability = 1e-2;
  const NoiseWeights noise = NoiseFromData(logs);
  const EkfResult in_memory = RunEkf(vehicle, logs, noise, options);
  ASSERT_TRUE(in_memory.usable) << in_memory.failure;

  std::vector<std::vector<int>> keep;
  for (const EstimationLog& log : logs) keep.push_back(WindowStartRows(log, 1.0));
  EkfHistoryFiles files(logs, vehicle.model.StateNames(), options.smoother, testing::TempDir(),
                        keep);
  const EkfResult streamed = RunEkf(vehicle, logs, noise, options, &files);
  ASSERT_TRUE(streamed.usable) << streamed.failure;
  EXPECT_TRUE(streamed.logs.empty());
  EXPECT_EQ(streamed.estimate, in_memory.estimate);
  EXPECT_EQ(streamed.settled_after_s, in_memory.settled_after_s);
  ASSERT_FALSE(in_memory.rejected.empty());  // the gate did reject samples

  EXPECT_EQ(Text([&](const EmitText& e) { files.StatesCsv(e); }),
            Text([&](const EmitText& e) { EkfStatesCsv(in_memory, e); }));
  EXPECT_EQ(Text([&](const EmitText& e) {
              files.ParametersCsv(streamed.free_names, streamed.covariance_pass, e);
            }),
            Text([&](const EmitText& e) { EkfParametersCsv(in_memory, e); }));
  EXPECT_EQ(Text([&](const EmitText& e) { files.InnovationsCsv(e); }),
            Text([&](const EmitText& e) { EkfInnovationsCsv(in_memory, e); }));

  for (size_t L = 0; L < logs.size(); ++L) {
    const EkfLogHistory& thin = files.thinned()[L];
    const EkfLogHistory& full = in_memory.logs[L];
    ASSERT_FALSE(thin.rows.empty());
    EXPECT_EQ(thin.rows.back(), logs[L].NumRows() - 1);  // the end of the time axis
    for (size_t i = 0; i < thin.rows.size(); ++i) {
      const int row = thin.rows[i];
      EXPECT_EQ(thin.times[i], full.times[row]);
      EXPECT_EQ(thin.states.row(i), full.states.row(row));
      EXPECT_EQ(thin.smoothed_states.row(i), full.smoothed_states.row(row));
      EXPECT_EQ(thin.parameters.row(i), full.parameters.row(row));
      EXPECT_EQ(thin.parameter_std.row(i), full.parameter_std.row(row));
      const Eigen::ArrayXd a = thin.innovations.row(i).transpose().array();
      const Eigen::ArrayXd b = full.innovations.row(row).transpose().array();
      EXPECT_TRUE(((a == b) || (a.isNaN() && b.isNaN())).all()) << "row " << row;
      EXPECT_EQ(thin.nis_dof[i], full.nis_dof[row]);
    }
    for (const bool smoothed : {false, true}) {
      const std::vector<Eigen::VectorXd> states =
          files.states_at_rows().Reported(static_cast<int>(L), smoothed);
      ASSERT_EQ(states.size(), keep[L].size());
      for (size_t w = 0; w < keep[L].size(); ++w) {
        const Eigen::MatrixXd& expected = smoothed ? full.smoothed_states : full.states;
        EXPECT_EQ(states[w].transpose(), expected.row(keep[L][w]));
      }
    }
  }
}

}  // namespace
}  // namespace coaxid
