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
    "           output_error: [--segment_s=1] [--start=config|linear_kf] [--huber=0]\n"
    "  discover --logs=A.csv[,B.csv...] --config=F --out=DIR [--validate=C.csv,...]\n"
    "           [--alpha=0.01] [--max_added=4] [--segment_s=1]\n"
    "  import   --format=tmotor28 --in=DIR --out=DIR2\n"
    "  study    --spec=FILE --out=DIR [--jobs=N] [--restart] [--max_runs=N]\n"
    "           --spec=FILE --out=DIR --export=N | --job=DIR/jobs/job_K.yaml | --merge --out=DIR\n"
    "           (mpirun -n K coaxid study ... in a -DCOAXID_MPI=ON build; docs/study.md)\n"
    "  demo     --out=DIR\n"
    "Run `coaxid --help` for every flag.\n";

void RequireFlag(const std::string& value, const char* name) {
  if (value.empty()) throw InputError(std::string("missing --") + name + "\n" + kUsage);
}

// Creates the output folder (and parents). Throws InputError if impossible.
void MakeOutputFolder(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    throw InputError("cannot create output folder '" + dir + "': " + ec.message());
  }
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

int Simulate() {
  RequireFlag(FLAGS_config, "config");
  RequireFlag(FLAGS_scenario, "scenario");
  RequireFlag(FLAGS_out, "out");
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
  RequireFlag(FLAGS_logs, "logs");
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

// The logs the demo simulates and the project ships (data/glmav/NAME.csv),
// each from configs/scenarios/NAME.yaml with configs/glmav.yaml.
const char* const kDemoScenarios[] = {"balance", "balance_points", "flight", "flight_3211",
                                      "balance_wake"};

int Demo() {
  RequireFlag(FLAGS_out, "out");
  const std::string root = FLAGS_data_dir;
  const std::string config_path = root + "/configs/glmav.yaml";
  const VehicleConfig config = LoadVehicleConfig(config_path);
  std::vector<Scenario> scenarios;
  for (const char* name : kDemoScenarios) {
    scenarios.push_back(LoadScenario(root + "/configs/scenarios/" + name + ".yaml"));
  }
  MakeOutputFolder(FLAGS_out);
  MakeOutputFolder(FLAGS_out + "/logs");

  std::string markdown =
      "# coaxid demo\n\nVehicle: `" + config_path +
      "` (the reference GLMAV of model.md). Each shipped scenario is simulated again from its "
      "seed and compared with the log the project ships in `data/glmav/`.\n\n";
  nlohmann::json report = {{"vehicle_config", config_path}, {"logs", nlohmann::json::array()}};
  const auto start = std::chrono::steady_clock::now();
  for (size_t i = 0; i < scenarios.size(); ++i) {
    const Scenario& s = scenarios[i];
    std::fprintf(stderr, "demo: [%zu/%zu] simulating %s ... ", i + 1, scenarios.size(),
                 s.name.c_str());
    const auto t0 = std::chrono::steady_clock::now();
    const Vehicle truth = MakeTruthVehicle(config, s);
    Log log = SimulateScenario(truth, s);
    const std::string out_log = FLAGS_out + "/logs/" + s.name + ".csv";
    WriteLog(out_log, log);
    WriteJson(FLAGS_out + "/logs/" + s.name + ".truth.json", TruthJson(truth));
    log = ReadLog(out_log);
    const double elapsed = Seconds(t0);
    std::fprintf(stderr, "%d rows in %.2f s (elapsed %.1f s)\n", log.NumRows(), elapsed,
                 Seconds(start));

    // Reproducibility: the shipped log must be what the seed gives.
    const std::string shipped_path = root + "/data/glmav/" + s.name + ".csv";
    std::string reproduced = "no shipped log to compare with";
    double max_difference = NAN;
    if (fs::exists(shipped_path)) {
      const Log shipped = ReadLog(shipped_path);
      max_difference = 0;
      bool same_shape = shipped.columns == log.columns && shipped.NumRows() == log.NumRows();
      if (same_shape) {
        for (size_t c = 0; c < log.columns.size(); ++c) {
          for (int k = 0; k < log.NumRows(); ++k) {
            const double a = log.values[c][k], b = shipped.values[c][k];
            if (std::isnan(a) != std::isnan(b)) same_shape = false;
            if (!std::isnan(a)) max_difference = std::max(max_difference, std::fabs(a - b));
          }
        }
      }
      reproduced = !same_shape ? "differs in shape from the shipped log"
                   : max_difference == 0 ? "identical to the shipped log"
                                         : "differs from the shipped log by at most " +
                                               std::to_string(max_difference);
    }
    const nlohmann::json summary = SummarizeLog(log);
    markdown += SummaryMarkdown(s.name + " (`logs/" + s.name + ".csv`, seed " +
                                    std::to_string(s.seed) + "; " + reproduced + ")",
                                summary);
    report["logs"].push_back({{"scenario", s.name},
                              {"log", out_log},
                              {"truth", FLAGS_out + "/logs/" + s.name + ".truth.json"},
                              {"simulation_seconds", elapsed},
                              {"shipped", shipped_path},
                              {"reproduced", reproduced},
                              {"summary", summary}});
  }
  // The estimators on the shipped logs, each into its own folder.
  struct Run {
    const char* method;
    std::vector<std::string> logs;
    const char* truth;
  };
  const Run runs[] = {
      {"linear_kf", {root + "/data/glmav/balance.csv"}, "balance"},
      {"output_error",
       {root + "/data/glmav/flight.csv", root + "/data/glmav/balance_points.csv"},
       "flight"},
  };
  markdown += "## Estimates on the shipped logs\n\n";
  nlohmann::json estimates = nlohmann::json::object();
  for (const Run& run : runs) {
    std::fprintf(stderr, "demo: identify --method=%s (elapsed %.1f s)\n", run.method,
                 Seconds(start));
    std::string logs;
    for (const auto& l : run.logs) logs += (logs.empty() ? "" : ",") + l;
    FLAGS_method = run.method;
    FLAGS_logs = logs;
    FLAGS_config = config_path;
    const std::string out = FLAGS_out;
    FLAGS_out = out + "/" + run.method;
    const int status = RunIdentify();
    FLAGS_out = out;
    if (status != 0) return status;
    const nlohmann::json r = nlohmann::json::parse(ReadFile(out + "/" + run.method + "/report.json"));
    estimates[run.method] = r["parameters"];
    markdown += "- `" + std::string(run.method) + "` on " + logs + ": `" + run.method +
                "/report.json`, plots in `" + run.method + "/plots/`\n";
  }
  const nlohmann::json truth =
      nlohmann::json::parse(ReadFile(FLAGS_out + "/logs/flight.truth.json"))["parameters"];
  markdown += "\n| parameter | truth | linear_kf | output_error |\n|---|---|---|---|\n";
  auto cell = [](const nlohmann::json& p) -> std::string {
    if (p.is_null()) return "-";
    char text[96];
    if (p.contains("estimated") && !p["estimated"].get<bool>()) {
      std::snprintf(text, sizeof text, "%.5g (config)", p["value"].get<double>());
    } else if (p["std"].is_number()) {
      std::snprintf(text, sizeof text, "%.5g ± %.2g", p["value"].get<double>(),
                    p["std"].get<double>());
    } else {
      std::snprintf(text, sizeof text, "%.5g (not identifiable)", p["value"].get<double>());
    }
    return text;
  };
  for (const char* name : {"alpha", "beta", "sigma0", "Cx", "Cy", "Cz", "gamma1", "gamma2", "d",
                           "Ixx", "Iyy", "Izz"}) {
    char t[32];
    std::snprintf(t, sizeof t, "%.5g", truth[name].get<double>());
    const auto kf = estimates["linear_kf"].contains(name) ? estimates["linear_kf"][name]
                                                          : nlohmann::json();
    markdown += std::string("| ") + name + " | " + t + " | " + cell(kf) + " | " +
                cell(estimates["output_error"][name]) + " |\n";
  }
  markdown +=
      "\nlinear_kf takes d and Cz from the config (model.md, decision 6), so a wrong d biases "
      "beta and Cz_beta (its report says so); output_error estimates everything jointly from "
      "the flight and balance logs.\n";
  report["estimates"] = estimates;

  // The closing loop: a simulated log with an effect the config does not
  // declare, and the measured coaxial test-stand data.
  struct Discovery {
    const char* name;
    std::string logs, config, title;
  };
  const std::string real = root + "/data/real/tmotor28-coaxial/";
  const Discovery discoveries[] = {
      {"discover_simulated", root + "/data/glmav/balance_wake.csv", config_path,
       "simulated balance log with an undeclared wake_interference (truth: k_T = 5e-6, "
       "k_Q = 1e-7)"},
      {"discover_tmotor28", real + "tmotor28_coaxial.csv," + real + "tmotor28_isolated.csv",
       root + "/configs/tmotor28.yaml",
       "measured T-motor 28\" coaxial test-stand data (pyBEMT, MIT licence), the paper's "
       "model with one sigma"}};
  markdown += "\n## The closing loop (`coaxid discover`)\n\n";
  nlohmann::json discovery_summary = nlohmann::json::object();
  for (const Discovery& d : discoveries) {
    std::fprintf(stderr, "demo: discover on the %s (elapsed %.1f s)\n", d.title.c_str(),
                 Seconds(start));
    const std::string out = FLAGS_out;
    FLAGS_logs = d.logs;
    FLAGS_config = d.config;
    FLAGS_out = out + "/" + d.name;
    const int status = RunDiscover();
    FLAGS_out = out;
    if (status != 0) return status;
    const nlohmann::json r =
        nlohmann::json::parse(ReadFile(out + "/" + d.name + "/discovery.json"));
    discovery_summary[d.name] = {{"added", r["added"]}, {"unexplained", r["unexplained"]}};
    std::string added;
    for (const auto& a : r["added"]) added += (added.empty() ? "" : ", ") + a.get<std::string>();
    markdown += "- " + d.title + ": added **" + (added.empty() ? "nothing" : added) +
                "**; the full report is `" + d.name + "/report.md`.\n";
  }
  report["discoveries"] = discovery_summary;
  WriteFileAtomically(FLAGS_out + "/summary.md", markdown);
  WriteJson(FLAGS_out + "/summary.json", report);
  std::fprintf(stderr, "demo: done in %.1f s; read %s/summary.md\n", Seconds(start),
               FLAGS_out.c_str());
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
    if (command == "demo") return Demo();
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
