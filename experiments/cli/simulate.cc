#include "experiments/cli/simulate.h"

#include <chrono>
#include <cstdio>

#include "core/log.h"
#include "core/report.h"
#include "core/stopwatch.h"
#include "core/vehicle_config.h"
#include "dynamics/vehicle.h"
#include "experiments/cli/cli.h"
#include "experiments/cli/flag_checks.h"
#include "experiments/cli/flags.h"
#include "experiments/simulation/scenario.h"
#include "experiments/simulation/simulate_experiment.h"

namespace coaxid {

int RunSimulate() {
  RequireFlag(FLAGS_config, "config", kCliUsage);
  RequireFlag(FLAGS_scenario, "scenario", kCliUsage);
  RequireFlag(FLAGS_out, "out", kCliUsage);
  const VehicleConfig config = LoadVehicleConfig(FLAGS_config);
  Scenario scenario = LoadScenario(FLAGS_scenario);
  if (FLAGS_seed >= 0) scenario.seed = static_cast<uint64_t>(FLAGS_seed);
  const Vehicle truth = MakeTruthVehicle(config, scenario);
  const auto start = std::chrono::steady_clock::now();
  const Log log = SimulateScenario(truth, scenario);
  // Write only after everything succeeded: nothing half-written.
  WriteLog(FLAGS_out, log);
  if (!FLAGS_truth.empty()) {
    nlohmann::json truth_json = TruthJson(truth);
    // Loads outside the library live in the scenario, not in the parameters.
    if (!scenario.truth_outside_library.empty()) {
      truth_json["outside_library"] = scenario.truth_outside_library;
    }
    WriteJson(FLAGS_truth, truth_json);
  }
  std::fprintf(stderr, "simulate: %s log, %d rows, %.2f s simulated in %.3f s -> %s\n",
               LogKindName(log.kind), log.NumRows(),
               log.Column("t").back() - log.Column("t").front(), SecondsSince(start),
               FLAGS_out.c_str());
  return 0;
}

}  // namespace coaxid
