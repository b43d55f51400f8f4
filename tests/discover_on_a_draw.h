// A fixture for the CLI tests of the closing loop on one randomised draw of a
// study spec (experiments/studies/random_draw.h): its flight, balance (if
// drawn) and held-out logs simulated into the test's folder and `coaxid discover` run on
// them the way a user would.
#pragma once

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/log.h"
#include "experiments/simulation/simulate_experiment.h"
#include "experiments/studies/random_draw.h"
#include "experiments/studies/spec.h"
#include "tests/cli_test_dir.h"
#include "tests/run_coaxid.h"

namespace coaxid {

class DiscoverOnADraw : public CliTestDir {
 protected:
  // The randomised spec of the confusion study (issue 13).
  static StudySpec ConfusionSpec() {
    return LoadStudySpec(std::string(COAXID_SOURCE_DIR) +
                         "/configs/studies/discover_confusion.yaml");
  }

  // ... and of the controllers' study (each run its own controller and sensors).
  static StudySpec ControllersSpec() {
    return LoadStudySpec(std::string(COAXID_SOURCE_DIR) +
                         "/configs/studies/discover_controllers.yaml");
  }

  // discovery.json of `coaxid discover` on the draw's flight log (and its
  // balance log, if it has one: draw.scenarios, in that order) with its
  // held-out flight; null, with a test failure, when the draw lacks the
  // flight or the held-out flight, or the program fails. The logs and
  // outputs go to the test's folder, their names led by `prefix`; `flags`
  // are added to the command line.
  nlohmann::json Discover(const StudySpec& spec, const RandomDraw& draw,
                          const std::string& prefix = "", const std::string& flags = "") {
    if (draw.scenarios.empty() || draw.scenarios.size() > 2 || !draw.has_held_out) {
      ADD_FAILURE() << "the draw holds " << draw.scenarios.size()
                    << " estimation logs (a flight, and a balance log or none, wanted) and "
                    << (draw.has_held_out ? "a" : "no") << " held-out flight";
      return nullptr;
    }
    const auto simulate = [&](const Scenario& s, const std::string& name) {
      WriteLog(Path(name), SimulateScenario(MakeTruthVehicle(spec.config, s), s));
      return Path(name);
    };
    std::string logs = simulate(draw.scenarios.at(0), prefix + "flight.csv");
    if (draw.scenarios.size() == 2) logs += "," + simulate(draw.scenarios.at(1), prefix + "balance.csv");
    const std::string held_out = simulate(draw.held_out, prefix + "held_out.csv");
    const RunResult run =
        RunCoaxid("discover --config=" + config_ + " --logs=" + logs + " --validate=" + held_out +
                  " --noise_relaxations=1 --out=" + Path(prefix + "out") +
                  (flags.empty() ? "" : " " + flags));
    if (run.status != 0) {
      ADD_FAILURE() << run.output;
      return nullptr;
    }
    std::ifstream in(Path(prefix + "out/discovery.json"));
    return nlohmann::json::parse(in);
  }

  // The confusion spec's draw of `seed` (*draw), which must be flight only
  // and hold `truth`, through Discover; null, with a test failure, if not.
  nlohmann::json DiscoverFlightOnly(uint64_t seed, const std::string& truth, RandomDraw* draw,
                                    const std::string& flags = "") {
    const StudySpec spec = ConfusionSpec();
    *draw = DrawRun(spec, seed);
    if (draw->truth_label != truth || draw->scenarios.size() != 1) {
      ADD_FAILURE() << "seed " << seed << " draws " << draw->truth_label << " with "
                    << draw->scenarios.size() << " estimation logs (" << truth
                    << ", flight only, wanted)";
      return nullptr;
    }
    return Discover(spec, *draw, "", flags);
  }

  // The effects a discovery.json added, sorted.
  static std::vector<std::string> SortedAdded(const nlohmann::json& j) {
    std::vector<std::string> added = j["added"].get<std::vector<std::string>>();
    std::sort(added.begin(), added.end());
    return added;
  }
};

}  // namespace coaxid
