// A small coaxial helicopter the paper's model lacks a part of (issue 17),
// run as a user would: a CoaX flight with its stabilizer bar
// (configs/scenarios/coax_flight.yaml, 44 s at 150 Hz) identified with
// configs/coax.yaml, which has no bar. The EKF survives it by raising its
// process noise from the data; output_error ends in bounded effort with a
// report; both say plainly that the model does not describe the vehicle,
// naming p and q. With the bar declared, output_error recovers it; the EKF
// refuses it for now (exit 2, nothing written); simulate flies it.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "tests/cli_test_dir.h"
#include "tests/run_coaxid.h"

namespace coaxid {
namespace {

namespace fs = std::filesystem;

const std::string kCoax = std::string(COAXID_SOURCE_DIR) + "/configs/coax.yaml";

class CoaxCliTest : public CliTestDir {
 protected:
  std::string SimulateCoaxFlight() {
    const std::string log = Path("coax.csv");
    const RunResult r = RunCoaxid("simulate --config=" + kCoax + " --scenario=" +
                                  std::string(COAXID_SOURCE_DIR) +
                                  "/configs/scenarios/coax_flight.yaml --out=" + log);
    EXPECT_EQ(r.status, 0) << r.output;
    return log;
  }

  // configs/coax.yaml with the stabilizer bar declared at these values.
  std::string CoaxConfigWithBar(double T_b, double k_b, double d_u) {
    const std::string config = Path("coax_bar.yaml");
    std::string text = ReadFile(kCoax);
    const std::string at = "effects:\n";
    text.replace(text.rfind(at), at.size(),
                 at + "  stabilizer_bar: {T_b: {value: " + std::to_string(T_b) +
                     "}, k_b: {value: " + std::to_string(k_b) + "}, d_u: {value: " +
                     std::to_string(d_u) + "}}\n");
    std::ofstream(config) << text;
    return config;
  }

  // The simulated flight's bar (T_b 1.8 s, k_b 0.6, d_u 0.165 m) within 3 of
  // the std a report gives.
  static void ExpectTheFlightsBar(const nlohmann::json& report) {
    const std::pair<const char*, double> truth[] = {
        {"stabilizer_bar.T_b", 1.8}, {"stabilizer_bar.k_b", 0.6}, {"stabilizer_bar.d_u", 0.165}};
    for (const auto& [name, value] : truth) {
      const nlohmann::json& p = report["parameters"][name];
      ASSERT_TRUE(p["std"].is_number()) << name << ": " << p.dump();
      EXPECT_LT(std::fabs(p["value"].get<double>() - value), 3 * p["std"].get<double>())
          << name << ": " << p.dump();
    }
  }

  // The channels a report's plausibility verdict names as unexplained.
  static std::set<std::string> Unexplained(const nlohmann::json& report) {
    std::set<std::string> out;
    for (const auto& f : report["plausibility"]["findings"]) {
      if (f["kind"] == "unexplained_channel") out.insert(f["subject"].get<std::string>());
    }
    return out;
  }
};

TEST_F(CoaxCliTest, TheEkfSurvivesAndSaysTheModelDoesNotDescribeTheVehicle) {
  const std::string log = SimulateCoaxFlight();
  // The default process noise alone loses the filter within 3 s.
  const RunResult fixed = RunCoaxid("identify --method=ekf --config=" + kCoax + " --logs=" + log +
                                    " --out=" + Path("fixed") +
                                    " --ekf_process_noise_from_data=false");
  EXPECT_EQ(fixed.status, 1) << fixed.output;
  EXPECT_TRUE(fixed.output.find("channel") != std::string::npos) << fixed.output;
  EXPECT_FALSE(fs::exists(Path("fixed") + "/report.json"));

  const RunResult r =
      RunCoaxid("identify --method=ekf --config=" + kCoax + " --logs=" + log + " --out=" + Path("ekf"));
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(Path("ekf") + "/report.json"));
  const nlohmann::json& from_data = report["ekf"]["process_noise"]["from_data"];
  EXPECT_GT(from_data["scale"].get<double>(), 1.0) << from_data.dump();
  EXPECT_FALSE(from_data["failures"].empty());
  EXPECT_EQ(report["plausibility"]["describes_vehicle"], false);
  const std::set<std::string> unexplained = Unexplained(report);
  EXPECT_TRUE(unexplained.count("p") && unexplained.count("q")) << report["plausibility"].dump();
  EXPECT_TRUE(r.output.find("THE MODEL DOES NOT DESCRIBE THIS VEHICLE") != std::string::npos);
}

TEST_F(CoaxCliTest, OutputErrorReportsWhatTheFitCannotDo) {
  const std::string log = SimulateCoaxFlight();
  const RunResult r = RunCoaxid("identify --method=output_error --config=" + kCoax +
                                " --logs=" + log + " --out=" + Path("oe"));
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(Path("oe") + "/report.json"));
  EXPECT_FALSE(report["convergence"]["stop_reason"].get<std::string>().empty());
  EXPECT_EQ(report["plausibility"]["describes_vehicle"], false);
  const std::set<std::string> unexplained = Unexplained(report);
  EXPECT_TRUE(unexplained.count("p") && unexplained.count("q")) << report["plausibility"].dump();
  // The inertias pressed to their bound far above what 0.30 kg of this size
  // can have (m r^2 = 0.0143 kg m^2).
  bool inertia_implausible = false;
  for (const auto& f : report["plausibility"]["findings"]) {
    inertia_implausible |= f["kind"] == "outside_physical_range" && f["subject"] == "Ixx";
  }
  EXPECT_TRUE(inertia_implausible) << report["plausibility"].dump();
}

// With the bar declared (from rough starting values), output_error carries
// its two states in every segment and recovers it: the truth's T_b 1.8 s,
// k_b 0.6, d_u 0.165 m within 3 of the reported std, and the fit is
// plausible.
TEST_F(CoaxCliTest, OutputErrorWithTheBarDeclaredRecoversIt) {
  const std::string log = SimulateCoaxFlight();
  const std::string config = CoaxConfigWithBar(1.0, 0.3, 0.15);
  const RunResult r = RunCoaxid("identify --method=output_error --config=" + config +
                                " --logs=" + log + " --out=" + Path("oe"));
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(Path("oe") + "/report.json"));
  ExpectTheFlightsBar(report);
  EXPECT_EQ(report["plausibility"]["describes_vehicle"], true) << report["plausibility"].dump();
}

// The EKF carries the bar's tilt (two states after the 12): declared 20 %
// off (T_b 1.5, k_b 0.5, d_u 0.15 against the flight's 1.8, 0.6, 0.165) it
// returns the bar within 3 of its reported std, and states.csv holds the
// tilt's estimates.
TEST_F(CoaxCliTest, TheEkfFitsABarInTheConfigAndReportsItsTilt) {
  const std::string log = SimulateCoaxFlight();
  const std::string config = CoaxConfigWithBar(1.5, 0.5, 0.15);
  const RunResult r = RunCoaxid("identify --method=ekf --config=" + config + " --logs=" + log +
                                " --out=" + Path("ekf"));
  ASSERT_EQ(r.status, 0) << r.output;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(Path("ekf") + "/report.json"));
  ExpectTheFlightsBar(report);
  // Neither the estimation nor the held-out tail loses the filter: the tail
  // starts its lagged rotors (motor_lag, 0.19 and 0.11 s) where the rows
  // before it left them (before, it took them as settled at their commands
  // and lost r within 0.25 s, whatever the process noise up to 1000 x).
  EXPECT_EQ(r.output.find("lost the filter"), std::string::npos) << r.output;
  const std::string states = ReadFile(Path("ekf") + "/states.csv");
  const std::string header = states.substr(0, states.find('\n'));
  EXPECT_NE(header.find(",stabilizer_bar.b_x,stabilizer_bar.b_x_std,"), std::string::npos) << header;
  EXPECT_NE(header.find(",stabilizer_bar.b_y_smoothed,"), std::string::npos) << header;
}

}  // namespace
}  // namespace coaxid
