#include "experiments/cli.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/log.h"
#include "core/report.h"
#include "dynamics/vehicle.h"
#include "experiments/cli_flags.h"
#include "experiments/command_checks.h"
#include "experiments/compare_command.h"
#include "experiments/demo_command.h"
#include "experiments/discover_command.h"
#include "experiments/identify_command.h"
#include "experiments/import_command.h"
#include "experiments/log_summary.h"
#include "experiments/scenario.h"
#include "experiments/simulate_experiment.h"
#include "experiments/study_command.h"

namespace coaxid {
namespace {

namespace fs = std::filesystem;

constexpr const char* kUsage =
    "usage: coaxid <subcommand> [--flags]\n"
    "  simulate --config=F --scenario=S --out=FILE.csv [--truth=T.json] [--seed=N]\n"
    "  check    --logs=A.csv[,B.csv...] [--config=F]\n"
    "  identify --method=linear_kf|output_error|ekf --logs=A.csv[,B.csv...] --config=F --out=DIR\n"
    "           [--validate=C.csv,...] [--holdout_fraction=0.2]\n"
    "           linear_kf: [--process_noise=0]\n"
    "           output_error: [--segment_s=1] [--start=config|linear_kf] [--huber=0] [--coloured_residuals]\n"
    "  discover --logs=A.csv[,B.csv...] --config=F --out=DIR [--validate=C.csv,...]\n"
    "           [--alpha=0.01] [--max_added=4] [--segment_s=1]\n"
    "  compare  --logs=A.csv[,B.csv...] --config=F --out=DIR [--validate=C.csv,...]\n"
    "           [--holdout_fraction=0.2] [--truth=T.json]\n"
    "           linear_kf (balance logs), output_error (all), ekf (flight logs); one table\n"
    "  import   --format=tmotor28 --in=DIR --out=DIR2\n"
    "  study    --spec=FILE --out=DIR [--jobs=N] [--restart] [--max_runs=N]\n"
    "           --spec=FILE --out=DIR --export=N | --job=DIR/jobs/job_K.yaml | --merge --out=DIR\n"
    "           (mpirun -n K coaxid study ... in a -DCOAXID_MPI=ON build; docs/study.md)\n"
    "  demo     --out=DIR   (the whole story on the shipped data -> DIR/report.html)\n"
    "Run `coaxid --help` for every flag.\n";

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

int Simulate() {
  RequireFlag(FLAGS_config, "config", kUsage);
  RequireFlag(FLAGS_scenario, "scenario", kUsage);
  RequireFlag(FLAGS_out, "out", kUsage);
  const VehicleConfig config = LoadVehicleConfig(FLAGS_config);
  Scenario scenario = LoadScenario(FLAGS_scenario);
  if (FLAGS_seed >= 0) scenario.seed = static_cast<uint64_t>(FLAGS_seed);
  const Vehicle truth = MakeTruthVehicle(config, scenario);
  const auto start = std::chrono::steady_clock::now();
  const Log log = SimulateScenario(truth, scenario);
  // Write only after everything succeeded: nothing half-written.
  WriteLog(FLAGS_out, log);
  if (!FLAGS_truth.empty()) WriteJson(FLAGS_truth, TruthJson(truth));
  std::fprintf(stderr, "simulate: %s log, %d rows, %.2f s simulated in %.3f s -> %s\n",
               LogKindName(log.kind), log.NumRows(),
               log.Column("t").back() - log.Column("t").front(), Seconds(start),
               FLAGS_out.c_str());
  return 0;
}

int Check() {
  RequireFlag(FLAGS_logs, "logs", kUsage);
  const std::vector<std::string> paths = SplitList(FLAGS_logs);
  if (paths.empty()) throw InputError("--logs names no file");
  std::vector<Log> logs;
  for (const std::string& path : paths) logs.push_back(ReadLog(path));
  for (const Log& log : logs) {
    const nlohmann::json summary = SummarizeLog(log);
    std::cout << SummaryMarkdown(log.source, summary);
  }
  std::cout << LinearKfCheckText(logs, FLAGS_config);
  std::cout << "check: " << logs.size() << " log(s) valid\n";
  return 0;
}

}  // namespace

std::vector<std::string> SplitList(const std::string& list) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= list.size()) {
    const size_t comma = list.find(',', start);
    const std::string part =
        list.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (!part.empty()) out.push_back(part);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

int RunCli(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << kUsage;
    return 2;
  }
  const std::string command = argv[1];
  if (argc > 2) {
    std::cerr << "coaxid: unexpected argument '" << argv[2] << "'\n" << kUsage;
    return 2;
  }
  try {
    if (command == "simulate") return Simulate();
    if (command == "check") return Check();
    if (command == "demo") return RunDemo();
    if (command == "compare") return RunCompare();
    if (command == "identify") return RunIdentify();
    if (command == "discover") return RunDiscover();
    if (command == "import") return RunImport();
    if (command == "study") return RunStudy();
    std::cerr << "coaxid: unknown subcommand '" << command << "'\n" << kUsage;
    return 2;
  } catch (const InputError& e) {
    std::cerr << "coaxid " << command << ": " << e.what() << "\n";
    return 2;
  } catch (const ComputationError& e) {
    std::cerr << "coaxid " << command << ": failed: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "coaxid " << command << ": internal error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace coaxid
