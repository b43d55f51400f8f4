// The CLI's contract (cli-and-reports.md): exit 0 on success, 2 on bad input
// with one clear message naming what and where, and nothing written to --out.
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "core/log.h"
#include "tests/run_coaxid.h"

namespace coaxid {
namespace {

namespace fs = std::filesystem;

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("coaxid_cli_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Write(const std::string& name, const std::string& text) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << text;
    return path;
  }
  std::string Source(const std::string& rel) { return std::string(COAXID_SOURCE_DIR) + "/" + rel; }
  fs::path dir_;
};

TEST_F(CliTest, SimulateWritesALogThatChecks) {
  const std::string out = (dir_ / "flight.csv").string();
  const std::string truth = (dir_ / "truth.json").string();
  const std::string scenario = Write("short.yaml",
                                     "scenario: flight\nseed: 3\nflight: {duration_s: 2}\n");
  RunResult r = RunCoaxid("simulate --config=" + Source("configs/glmav.yaml") +
                    " --scenario=" + scenario + " --out=" + out + " --truth=" + truth);
  ASSERT_EQ(r.status, 0) << r.output;
  const Log log = ReadLog(out);
  EXPECT_EQ(log.kind, LogKind::kFlight);
  EXPECT_EQ(log.NumRows(), 401);  // 2 s at 200 Hz, both ends
  EXPECT_TRUE(fs::exists(truth));
  r = RunCoaxid("check --logs=" + out);
  EXPECT_EQ(r.status, 0) << r.output;
}

TEST_F(CliTest, SimulateIsReproducibleFromTheSeed) {
  const std::string scenario = Write("s.yaml", "scenario: flight\nseed: 5\nflight: {duration_s: 1}\n");
  const std::string a = (dir_ / "a.csv").string(), b = (dir_ / "b.csv").string();
  const std::string args = "simulate --config=" + Source("configs/glmav.yaml") + " --scenario=" + scenario;
  ASSERT_EQ(RunCoaxid(args + " --out=" + a).status, 0);
  ASSERT_EQ(RunCoaxid(args + " --out=" + b).status, 0);
  const Log la = ReadLog(a), lb = ReadLog(b);
  EXPECT_EQ(la.values, lb.values);
  const std::string c = (dir_ / "c.csv").string();
  ASSERT_EQ(RunCoaxid(args + " --out=" + c + " --seed=6").status, 0);
  EXPECT_NE(ReadLog(c).values, la.values);
}

// Each bad-input case of log-format.md: exit 2, a message naming the file, the
// line and the column.
TEST_F(CliTest, CheckRefusesBadLogsWithExitTwo) {
  struct Case {
    std::string name, text, expected;
  };
  const std::string header = "t,omega1,omega2,delta_cx,delta_cy,phi,theta,psi,p,q,r\n";
  const std::string row0 = "0,150,160,0,0,0,0,0,0,0,0\n";
  const Case cases[] = {
      {"nokind.csv", header + row0, "kind"},
      {"missing.csv", "# kind: flight\nt,omega1,omega2,delta_cx,phi,theta,psi,p,q,r\n0,1,2,3,4,5,6,7,8,9\n",
       "delta_cy"},
      {"text.csv", "# kind: flight\n" + header + row0 + "0.005,150,abc,0,0,0,0,0,0,0,0\n",
       "omega2"},
      {"inf.csv", "# kind: flight\n" + header + row0 + "0.005,150,160,inf,0,0,0,0,0,0,0\n",
       "delta_cx"},
      {"time.csv", "# kind: flight\n" + header + row0 + "0,150,160,0,0,0,0,0,0,0,0\n", "time"},
      {"noload.csv", "# kind: balance\nt,omega1,omega2,delta_cx,delta_cy\n0,1,1,0,0\n", "load"},
  };
  for (const Case& c : cases) {
    const std::string path = Write(c.name, c.text);
    const RunResult r = RunCoaxid("check --logs=" + path);
    EXPECT_EQ(r.status, 2) << c.name << ": " << r.output;
    EXPECT_NE(r.output.find(c.name), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.name << ": " << r.output;
  }
  // A missing file is bad input too.
  EXPECT_EQ(RunCoaxid("check --logs=" + (dir_ / "absent.csv").string()).status, 2);
}

TEST_F(CliTest, BadConfigOrScenarioExitsTwoAndWritesNothing) {
  const std::string out = (dir_ / "never.csv").string();
  const std::string bad_config = Write("bad.yaml", "vehicle: x\nknown: {m: 0.25}\nunknown: {}\n");
  RunResult r = RunCoaxid("simulate --config=" + bad_config + " --scenario=flight --out=" + out);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("bad.yaml"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));

  const std::string bad_scenario = Write("s.yaml", "scenario: flight\nflight: {duraton_s: 3}\n");
  r = RunCoaxid("simulate --config=" + Source("configs/glmav.yaml") + " --scenario=" + bad_scenario +
          " --out=" + out);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("duraton_s"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));

  const std::string bad_effect =
      Write("e.yaml", "scenario: flight\ntruth: {effects: {magic_lift: {}}}\n");
  r = RunCoaxid("simulate --config=" + Source("configs/glmav.yaml") + " --scenario=" + bad_effect +
          " --out=" + out);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("magic_lift"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));

  EXPECT_EQ(RunCoaxid("frobnicate").status, 2);
  EXPECT_EQ(RunCoaxid("simulate --scenario=flight").status, 2);  // no --config
}

}  // namespace
}  // namespace coaxid
