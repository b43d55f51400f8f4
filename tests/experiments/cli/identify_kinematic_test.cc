// `coaxid identify --method=kinematic` run as a user would: the shipped
// flight log with a pitch-gyro bias added and its attitude logged 20 ms late
// gives both back within 3 std, writes a corrected log that the other
// methods read and whose reconstruction finds nothing left; a balance log
// exits 2 with --out untouched.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/log.h"
#include "tests/cli_test_dir.h"
#include "tests/run_coaxid.h"

namespace coaxid {
namespace {

namespace fs = std::filesystem;

class KinematicCliTest : public CliTestDir {
 protected:
  const std::string data_ = std::string(COAXID_SOURCE_DIR) + "/data/glmav/";
};

void ExpectNear3Std(const nlohmann::json& report, const char* name, double truth) {
  const auto& p = report["parameters"][name];
  ASSERT_TRUE(p["estimated"].get<bool>()) << name;
  const double value = p["value"], std = p["std"];
  EXPECT_GT(std, 0) << name;
  EXPECT_NEAR(value, truth, 3 * std) << name << " = " << value << " +- " << std;
}

TEST_F(KinematicCliTest, FindsAGyroBiasAndA20msAttitudeDelayAndCorrectsThem) {
  Log log = ReadLog(data_ + "flight.csv");
  std::vector<double> q = log.Column("q");
  for (double& v : q) v += 0.01;  // b_q [rad/s]
  log.SetColumn("q", q);
  for (const char* column : {"phi", "theta", "psi"}) {  // 4 rows at 200 Hz late
    const std::vector<double> v = log.Column(column);
    std::vector<double> late = v;
    for (size_t k = 0; k < v.size(); ++k) late[k] = v[k >= 4 ? k - 4 : 0];
    log.SetColumn(column, late);
  }
  WriteLog(Path("flight.csv"), log);
  const RunResult r = RunCoaxid("identify --method=kinematic --logs=" + Path("flight.csv") +
                                " --kinematic_scale_factors=false --out=" + Path("out"));
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(Contains(r.output, "kinematic: iteration")) << r.output;  // progress
  EXPECT_TRUE(Contains(r.output, "kinematic estimates")) << r.output;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(Path("out/report.json")));
  EXPECT_EQ(report["method"], "kinematic");
  ExpectNear3Std(report, "b_q", 0.01);
  ExpectNear3Std(report, "b_p", 0.0);
  EXPECT_FALSE(report["parameters"]["s_q"]["estimated"].get<bool>());
  // Only the attitude is late here; the positions and velocities are not,
  // so tau (one offset for all of them) lands between 0 and 20 ms.
  const double tau = report["parameters"]["tau"]["value"];
  EXPECT_GT(tau, 0.002);
  EXPECT_LT(tau, 0.020);
  for (const char* channel : {"x", "y", "z", "u", "v", "w", "phi", "theta", "psi"}) {
    EXPECT_TRUE(report["fit"][channel]["nrmse"].is_number()) << channel;
  }
  ASSERT_TRUE(fs::exists(Path("out/corrected_flight.csv")));
  EXPECT_TRUE(fs::exists(Path("out/fit_flight.csv")));

  // The corrected log reads back (the format is the input's) with the bias removed.
  const Log corrected = ReadLog(Path("out/corrected_flight.csv"));
  const double b_q = report["parameters"]["b_q"]["value"];
  EXPECT_NEAR(corrected.Column("q")[100], q[100] - b_q, 1e-12);
  const RunResult again = RunCoaxid("identify --method=kinematic --logs=" +
                                    Path("out/corrected_flight.csv") +
                                    " --kinematic_scale_factors=false --out=" + Path("again"));
  ASSERT_EQ(again.status, 0) << again.output;
  const nlohmann::json second = nlohmann::json::parse(ReadFile(Path("again/report.json")));
  ExpectNear3Std(second, "b_q", 0.0);
}

TEST_F(KinematicCliTest, RefusesABalanceLogWithExitTwoAndWritesNothing) {
  const RunResult r = RunCoaxid("identify --method=kinematic --logs=" + data_ +
                                "balance.csv --out=" + Path("out"));
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_TRUE(Contains(r.output, "flight logs")) << r.output;
  EXPECT_FALSE(fs::exists(Path("out")));
}

}  // namespace
}  // namespace coaxid
