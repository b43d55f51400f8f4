// `coaxid design`, run as a user would: the predicted precision, the designed
// balance holds and their scenario file (which `simulate` flies); exit 2 with
// one message and nothing written on bad input.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/cli_test_dir.h"
#include "tests/run_coaxid.h"

namespace coaxid {
namespace {

namespace fs = std::filesystem;

class DesignCliTest : public CliTestDir {
 protected:
  std::string Design(const std::string& scenarios, const std::string& out,
                     const std::string& extra = "") const {
    return "design --config=" + config_ + " --scenario=" + scenarios + " --out=" + out + " " + extra;
  }
  const std::string balance_ = std::string(COAXID_SOURCE_DIR) + "/configs/scenarios/balance_short.yaml";
  const std::string flight_ = std::string(COAXID_SOURCE_DIR) + "/configs/scenarios/flight.yaml";
};

TEST_F(DesignCliTest, BadInputExitsTwoAndWritesNothing) {
  const std::string out = Path("out");
  const std::pair<std::string, std::string> cases[] = {
      {Design(balance_, out, "--criterion=E"), "--criterion"},
      {Design(balance_, out, "--design_parameters=Cq"), "not a parameter"},
      // Flight logs alone hold d for the scale: it cannot be designed for.
      {Design(flight_, out, "--design_parameters=d"), "held for the scale"},
      {Design(flight_, out, "--design_bands=1:0.5"), "--design_bands"},
      {Design(flight_, out, "--design_signal=chirp"), "--design_signal"},
      {Design(flight_, out, "--design_signal=3211 --design_pulse_widths_s=0.2,-1"),
       "--design_pulse_widths_s"},
      {Design(balance_, out, "--add_holds=1 --max_swashplate_rad=0.3"), "0.2 rad"},
      {Design(Path("missing.yaml"), out), "missing.yaml"},
  };
  for (const auto& [args, message] : cases) {
    const RunResult r = RunCoaxid(args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.output;
    EXPECT_TRUE(Contains(r.output, message)) << args << "\n" << r.output;
    EXPECT_FALSE(fs::exists(out)) << args;
  }
}

TEST_F(DesignCliTest, BalanceCampaignGetsHoldsThatSimulateFlies) {
  const std::string out = Path("out");
  const RunResult r = RunCoaxid(Design(balance_, out, "--add_holds=2 --design_parameters=beta,Cz"));
  ASSERT_EQ(r.status, 0) << r.output;
  std::ifstream in(out + "/design.json");
  const nlohmann::json design = nlohmann::json::parse(in);
  EXPECT_EQ(design["criterion"]["kind"], "D");
  EXPECT_EQ(design["balance"]["added_holds"].size(), 2u);
  for (const char* name : {"beta", "Cz", "d"}) {
    const double planned = design["predicted"]["parameters"][name]["std"];
    const double designed = design["final"]["parameters"][name]["std"];
    EXPECT_GT(planned, 0) << name;
    EXPECT_LE(designed, planned * (1 + 1e-9)) << name;  // holds only add information
  }
  EXPECT_TRUE(fs::exists(out + "/report.md"));
  const std::string designed = out + "/designed_balance_short.yaml";
  ASSERT_TRUE(fs::exists(designed));
  const RunResult sim = RunCoaxid("simulate --config=" + config_ + " --scenario=" + designed +
                                  " --out=" + Path("designed.csv"));
  EXPECT_EQ(sim.status, 0) << sim.output;
}

}  // namespace
}  // namespace coaxid
