// `coaxid discover` end to end: simulate a balance log with an undeclared
// effect, run the binary, read discovery.json; bad input exits 2 and writes
// nothing (cli-and-reports.md).
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace coaxid {
namespace {

namespace fs = std::filesystem;

int RunCoaxid(const std::string& args, std::string* output) {
  const std::string command = std::string(COAXID_BINARY) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  char buffer[4096];
  while (size_t n = fread(buffer, 1, sizeof buffer, pipe)) output->append(buffer, n);
  const int status = pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(DiscoverCli, FindsWakeInterferenceInASimulatedBalanceLog) {
  const fs::path dir = fs::temp_directory_path() / ("coaxid_discover_cli_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    std::ofstream scenario(dir / "wake.yaml");
    scenario << "scenario: balance\nseed: 3\nbalance:\n  rate_hz: 50\n  hold_s: 0.5\n"
                "truth:\n  effects: {wake_interference: {k_T: 5.0e-6, k_Q: 1.0e-7}}\n";
  }
  const std::string config = std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml";
  std::string out;
  ASSERT_EQ(RunCoaxid("simulate --config=" + config + " --scenario=" + (dir / "wake.yaml").string() +
                          " --out=" + (dir / "wake.csv").string(),
                      &out),
            0)
      << out;
  ASSERT_EQ(RunCoaxid("discover --config=" + config + " --logs=" + (dir / "wake.csv").string() +
                          " --out=" + (dir / "out").string(),
                      &out),
            0)
      << out;
  std::ifstream in(dir / "out" / "discovery.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["added"], nlohmann::json::array({"wake_interference"}));
  for (const char* key : {"baseline", "candidates", "final", "unexplained"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_TRUE(j["baseline"].contains("validation"));  // the held-out final part
  ASSERT_TRUE(j["seconds_by_step"].is_array());
  EXPECT_EQ(j["seconds_by_step"][0]["step"], "EKF start");  // tried first: no flight log here
  double summed = 0;
  for (const nlohmann::json& step : j["seconds_by_step"]) summed += step["seconds"].get<double>();
  EXPECT_LE(summed, j["seconds"].get<double>());
  EXPECT_LT(j["final"]["validation"]["N"]["nrmse"].get<double>(),
            0.5 * j["baseline"]["validation"]["N"]["nrmse"].get<double>());
  EXPECT_TRUE(fs::exists(dir / "out" / "report.md"));

  std::string bad;
  EXPECT_EQ(RunCoaxid("discover --config=" + config + " --logs=" + (dir / "missing.csv").string() +
                          " --out=" + (dir / "bad").string(),
                      &bad),
            2)
      << bad;
  EXPECT_FALSE(fs::exists(dir / "bad"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace coaxid
