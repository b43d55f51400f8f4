// `coaxid identify --method=ekf` run as a user would (cli-and-reports.md):
// report.json with the contract's fields and the EKF's consistency section,
// the CSV histories; exit 2 with one clear message and nothing written to
// --out on bad input, exit 1 when the filter diverges.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/log.h"
#include "tests/cli_test_dir.h"
#include "tests/run_coaxid.h"

namespace coaxid {
namespace {

namespace fs = std::filesystem;

class EkfCliTest : public CliTestDir {
 protected:
  // A 12 s flight of the shipped scenario (truth differs from the config).
  std::string SimulateFlight(const std::string& name) {
    const std::string scenario = Path("short.yaml");
    std::ofstream(scenario) << "scenario: flight\nseed: 41\nflight: {duration_s: 12}\n"
                               "truth:\n  parameters: {alpha: -5.9e-5, beta: -5.3e-5, "
                               "sigma0: 0.12, Cz: 1.3}\n";
    const RunResult r = RunCoaxid("simulate --config=" + config_ + " --scenario=" + scenario +
                                  " --out=" + Path(name));
    EXPECT_EQ(r.status, 0) << r.output;
    return Path(name);
  }
  std::string Identify(const std::string& logs, const std::string& out,
                       const std::string& extra = "") const {
    return "identify --method=ekf --logs=" + logs + " --config=" + config_ + " --out=" + out +
           " " + extra;
  }
};

TEST_F(EkfCliTest, WritesTheReportAndHistories) {
  const std::string log = SimulateFlight("flight.csv");
  const std::string out = Path("out");
  const RunResult r = RunCoaxid(Identify(log, out));
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_TRUE(Contains(r.output, "rows (")) << r.output;  // progress
  EXPECT_TRUE(Contains(r.output, "ekf estimates")) << r.output;

  const nlohmann::json report = nlohmann::json::parse(ReadFile(out + "/report.json"));
  EXPECT_EQ(report["method"], "ekf");
  ASSERT_EQ(report["logs"].size(), 1u);
  for (const char* name : {"alpha", "beta", "sigma0", "Cx", "Cy", "Cz", "gamma1", "gamma2",
                           "Ixx", "Iyy", "Izz"}) {
    const auto& p = report["parameters"][name];
    EXPECT_TRUE(p["value"].is_number()) << name;
    EXPECT_EQ(p["estimated"], true) << name;
    // A std, or none with the reason (9.6 s of flight leave Cz undetermined).
    if (p["identifiable"] == true) {
      EXPECT_TRUE(p["std"].is_number()) << name;
    } else {
      EXPECT_TRUE(p["std"].is_null()) << name;
      EXPECT_TRUE(p["note"].is_string()) << name;
    }
  }
  for (const char* name : {"alpha", "beta", "gamma1", "Ixx"}) {
    EXPECT_EQ(report["parameters"][name]["identifiable"], true) << name;
  }
  // d holds the scale (model.md decision 8): not estimated, and said so.
  EXPECT_EQ(report["parameters"]["d"]["estimated"], false);
  EXPECT_TRUE(report["parameters"]["d"]["std"].is_null());
  EXPECT_TRUE(Contains(report["parameters"]["d"]["source"].get<std::string>(), "held for the scale"));
  EXPECT_EQ(report["parameters"]["d"]["held_for_the_scale"], true);
  EXPECT_EQ(report["scale"]["held"], "d");
  EXPECT_TRUE(report["ratios"]["d*beta/Ixx"]["std"].is_number());
  EXPECT_EQ(report["parameters"]["m"]["estimated"], false);
  // Fit and validation: every channel, overall nrmse, what "model" means.
  for (const char* section : {"fit", "validation"}) {
    const auto& s = report[section];
    EXPECT_TRUE(s["overall_nrmse"].is_number()) << section;
    for (const char* channel : {"phi", "p", "az", "x"}) {
      EXPECT_TRUE(s[channel]["rms"].is_number()) << section << " " << channel;
      EXPECT_TRUE(s[channel]["nrmse"].is_number()) << section << " " << channel;
    }
    EXPECT_EQ(s["window_s"], 1.0);
  }
  EXPECT_TRUE(Contains(report["validation"]["data"].get<std::string>(), "rows"));
  // Consistency: NIS with its band, per channel.
  EXPECT_TRUE(report["ekf"]["nis"]["all"]["band_95"].is_array());
  EXPECT_TRUE(report["ekf"]["nis"]["channels"].contains("q"));
  EXPECT_EQ(report["ekf"]["passes"], 2);
  // A flight of the config's own vehicle: the fit is plausible (issue 17).
  EXPECT_EQ(report["plausibility"]["describes_vehicle"], true) << report["plausibility"].dump();

  // Histories: one row per log row (80 % of 2401 rows estimated).
  for (const char* file : {"states.csv", "parameters.csv", "innovations.csv", "config.yaml",
                           "estimated_config.yaml", "fit_flight.csv", "validation_flight.csv"}) {
    EXPECT_TRUE(fs::exists(out + "/" + file)) << file;
  }
  const std::string states = ReadFile(out + "/states.csv");
  EXPECT_EQ(states.substr(0, states.find('\n')).substr(0, 16), "log,t,x,x_std,y,");
  EXPECT_EQ(std::count(states.begin(), states.end(), '\n'), 1 + 1921);
  const std::string parameters = ReadFile(out + "/parameters.csv");
  EXPECT_TRUE(Contains(parameters.substr(0, parameters.find('\n')), "Izz_std_at_estimate"));
  const std::string config = ReadFile(out + "/estimated_config.yaml");
  EXPECT_TRUE(Contains(config, "alpha"));
}

TEST_F(EkfCliTest, StartsFromAnEarlierReport) {
  // Initial values and std from a report.json (e.g. output_error's on other
  // data); the one-pass filter without smoother (the online configuration).
  const std::string log = SimulateFlight("flight.csv");
  std::ofstream(Path("start.json"))
      << R"({"method": "output_error", "parameters": {"alpha": {"value": -5.8e-5, )"
      << R"("std": 2e-6, "estimated": true}, "sigma0": {"value": 0.11, "std": null}}})";
  const std::string out = Path("out");
  const RunResult r = RunCoaxid(Identify(log, out,
                                         "--ekf_initial_report=" + Path("start.json") +
                                             " --smoother=false --ekf_covariance_pass=false"));
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(out + "/report.json"));
  EXPECT_DOUBLE_EQ(report["parameters"]["alpha"]["initial"].get<double>(), -5.8e-5);
  EXPECT_NEAR(report["parameters"]["alpha"]["initial_std"].get<double>(), 2e-6, 1e-15);
  EXPECT_DOUBLE_EQ(report["parameters"]["sigma0"]["initial"].get<double>(), 0.11);
  EXPECT_NEAR(report["parameters"]["sigma0"]["initial_std"].get<double>(), 0.05, 1e-12);
  EXPECT_EQ(report["ekf"]["passes"], 1);
  EXPECT_EQ(report["ekf"]["smoother"], false);
  // An out-of-bounds start is bad input.
  std::ofstream(Path("bad.json")) << R"({"parameters": {"alpha": {"value": 1.0}}})";
  const RunResult bad = RunCoaxid(Identify(log, Path("out2"),
                                           "--ekf_initial_report=" + Path("bad.json")));
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_TRUE(Contains(bad.output, "bounds")) << bad.output;
  EXPECT_FALSE(fs::exists(Path("out2")));
}

TEST_F(EkfCliTest, BadInputExitsTwoAndWritesNothing) {
  const std::string out = Path("out");
  const std::string balance = std::string(COAXID_SOURCE_DIR) + "/data/glmav/balance_points.csv";
  RunResult r = RunCoaxid(Identify(balance, out));
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_TRUE(Contains(r.output, "flight logs")) << r.output;
  EXPECT_FALSE(fs::exists(out));
  const std::string log = SimulateFlight("flight.csv");
  r = RunCoaxid(Identify(log, out, "--ekf_scale_anchor=Ixx"));
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_TRUE(Contains(r.output, "--ekf_scale_anchor")) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(EkfCliTest, DivergenceExitsOneAndWritesNothing) {
  // A roll sensor fault (+0.5 rad from t = 6 s): the innovation gate rejects
  // every phi sample from then on, and after 0.25 s the filter stops with the
  // channel and the time; with the gate off, the filter diverges.
  Log log = ReadLog(SimulateFlight("flight.csv"));
  std::vector<double> phi = log.Column("phi");
  for (int k = 0; k < log.NumRows(); ++k) {
    if (log.Column("t")[k] >= 6.0) phi[k] += 0.5;
  }
  log.SetColumn("phi", phi);
  WriteLog(Path("fault.csv"), log);
  const std::string out = Path("out");
  RunResult r = RunCoaxid(Identify(Path("fault.csv"), out, "--holdout_fraction=0"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_TRUE(Contains(r.output, "channel phi: every sample since t = 6.000 s rejected"))
      << r.output;
  EXPECT_FALSE(fs::exists(out + "/report.json"));
  r = RunCoaxid(Identify(Path("fault.csv"), out,
                         "--holdout_fraction=0 --ekf_gate=0 --ekf_process_noise_from_data=false"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_TRUE(Contains(r.output, "diverged")) << r.output;
  EXPECT_FALSE(fs::exists(out + "/report.json"));
  // Without the gate, the process noise raised from the data lets the rates
  // absorb the fault: the run ends, and its verdict says the fit is not the
  // vehicle's (issue 17).
  r = RunCoaxid(Identify(Path("fault.csv"), out, "--holdout_fraction=0 --ekf_gate=0"));
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(out + "/report.json"));
  EXPECT_GT(report["ekf"]["process_noise"]["from_data"]["scale"].get<double>(), 1.0);
  EXPECT_EQ(report["plausibility"]["describes_vehicle"], false) << report["plausibility"].dump();
}

}  // namespace
}  // namespace coaxid
