#include "experiments/cli/demo.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/log.h"
#include "core/report.h"
#include "core/report_values.h"
#include "core/stopwatch.h"
#include "dynamics/vehicle.h"
#include "experiments/cli/compare.h"
#include "experiments/cli/discover.h"
#include "experiments/cli/flag_checks.h"
#include "experiments/cli/flags.h"
#include "experiments/reports/demo_report.h"
#include "experiments/reports/log_summary.h"
#include "experiments/reports/markdown_html.h"
#include "experiments/simulation/scenario.h"
#include "experiments/simulation/simulate_experiment.h"

namespace coaxid {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

// The logs the demo simulates and the project ships (data/glmav/NAME.csv),
// each from configs/scenarios/NAME.yaml with configs/glmav.yaml.
const char* const kDemoScenarios[] = {"balance", "balance_points", "flight", "flight_3211",
                                      "balance_wake"};

// "identical to the shipped log", or how it differs, or that there is none.
std::string ReproducedText(const Log& log, const std::string& shipped_path) {
  if (!fs::exists(shipped_path)) return "no shipped log to compare with";
  const Log shipped = ReadLog(shipped_path);
  double max_difference = 0;
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
  return !same_shape ? "differs in shape from the shipped log"
         : max_difference == 0
             ? "identical to the shipped log"
             : "differs from the shipped log by at most " + NumberText(max_difference, "%.2g") +
                   (max_difference < 1e-9 ? " (floating-point rounding: a different build wrote it)"
                                          : "");
}

}  // namespace

int RunDemo() {
  if (FLAGS_out.empty()) throw InputError("missing --out\nusage: coaxid demo --out=DIR");
  const std::string out = FLAGS_out;
  const std::string root = FLAGS_data_dir;
  const std::string config_path = root + "/configs/glmav.yaml";
  const VehicleConfig config = LoadVehicleConfig(config_path);
  std::vector<Scenario> scenarios;
  for (const char* name : kDemoScenarios) {
    scenarios.push_back(LoadScenario(root + "/configs/scenarios/" + name + ".yaml"));
  }
  MakeOutputFolder(out + "/logs");

  DemoRecord record;
  record.config = config_path;
  json summary = {{"vehicle_config", config_path}, {"logs", json::array()}};
  const Clock::time_point start = Clock::now();

  // 1. Simulation, and reproducibility of the shipped logs.
  for (size_t i = 0; i < scenarios.size(); ++i) {
    const Scenario& s = scenarios[i];
    std::fprintf(stderr, "demo: [%zu/%zu] simulating %s ... ", i + 1, scenarios.size(),
                 s.name.c_str());
    const Clock::time_point t0 = Clock::now();
    const Vehicle truth = MakeTruthVehicle(config, s);
    DemoSimulatedLog entry;
    entry.scenario = s.name;
    entry.seed = s.seed;
    entry.log = "logs/" + s.name + ".csv";
    entry.truth = "logs/" + s.name + ".truth.json";
    WriteLog(out + "/" + entry.log, SimulateScenario(truth, s));
    WriteJson(out + "/" + entry.truth, TruthJson(truth));
    const Log log = ReadLog(out + "/" + entry.log);
    entry.rows = log.NumRows();
    entry.duration_s = log.Column("t").back() - log.Column("t").front();
    const double elapsed = SecondsSince(t0);
    std::fprintf(stderr, "%d rows in %.2f s (elapsed %.1f s)\n", entry.rows, elapsed,
                 SecondsSince(start));
    const std::string shipped = root + "/data/glmav/" + s.name + ".csv";
    entry.reproduced = ReproducedText(log, shipped);
    record.simulated.push_back(entry);
    summary["logs"].push_back({{"scenario", s.name},
                               {"log", entry.log},
                               {"truth", entry.truth},
                               {"simulation_seconds", elapsed},
                               {"shipped", shipped},
                               {"reproduced", entry.reproduced},
                               {"summary", SummarizeLog(log)}});
  }
  record.step_seconds.push_back({"1. simulate the shipped scenarios", SecondsSince(start)});

  // 2-5. The three estimators on the shipped logs, compared against the truth.
  const Clock::time_point compare_start = Clock::now();
  std::fprintf(stderr, "demo: compare linear_kf, output_error, ekf (elapsed %.1f s)\n",
               SecondsSince(start));
  CompareRequest compare;
  compare.logs = root + "/data/glmav/flight.csv," + root + "/data/glmav/balance.csv";
  compare.config = config_path;
  compare.out = out + "/compare";
  compare.truth = out + "/logs/flight.truth.json";
  compare.print_table = false;
  record.compare_folder = "compare";
  record.comparison = Compare(compare);
  for (const json& m : record.comparison["methods"]) {
    if (m["status"] == "ran") {
      record.reports[m["method"].get<std::string>()] =
          json::parse(ReadFile(compare.out + "/" + m["report"].get<std::string>()));
    }
    const double wall_s = m["wall_s"].is_number() ? m["wall_s"].get<double>() : 0.0;
    record.step_seconds.push_back({"identify --method=" + m["method"].get<std::string>(), wall_s});
  }
  record.step_seconds.push_back({"compare, in all", SecondsSince(compare_start)});
  summary["compare"] = record.comparison;

  // 6. The closing loop: simulated logs with an effect the config does not
  // declare (a balance log of the GLMAV; a Skybotix CoaX flight with its
  // stabilizer bar, issue 17), and the measured coaxial test-stand data.
  const std::string real = root + "/data/real/tmotor28-coaxial/";
  const std::string coax_config = root + "/configs/coax.yaml";
  {
    const Scenario coax = LoadScenario(root + "/configs/scenarios/coax_flight.yaml");
    const Vehicle truth = MakeTruthVehicle(LoadVehicleConfig(coax_config), coax);
    WriteLog(out + "/logs/coax_flight.csv", SimulateScenario(truth, coax));
    WriteJson(out + "/logs/coax_flight.truth.json", TruthJson(truth));
  }
  struct Discovery {
    const char* folder;
    std::vector<std::string> logs;
    std::string config, title;
  };
  const Discovery discoveries[] = {
      {"discover_simulated",
       {root + "/data/glmav/balance_wake.csv"},
       config_path,
       "Simulated balance log with an undeclared wake_interference (truth: k_T = 5e-6, "
       "k_Q = 1e-7)"},
      {"discover_coax",
       {out + "/logs/coax_flight.csv"},
       coax_config,
       "Simulated Skybotix CoaX flight (configs/scenarios/coax_flight.yaml, 44 s at 150 Hz, "
       "flight log alone) with a stabilizer bar that configs/coax.yaml lacks (truth: T_b = "
       "1.8 s, k_b = 0.6, d_u = 0.165 m)"},
      {"discover_tmotor28",
       {real + "tmotor28_coaxial.csv", real + "tmotor28_isolated.csv"},
       root + "/configs/tmotor28.yaml",
       "Measured T-motor 28\" coaxial test-stand data (pyBEMT, MIT licence), the paper's model "
       "with one sigma"}};
  summary["discoveries"] = json::object();
  for (const Discovery& d : discoveries) {
    std::fprintf(stderr, "demo: discover on the %s (elapsed %.1f s)\n", d.title.c_str(),
                 SecondsSince(start));
    const Clock::time_point t0 = Clock::now();
    std::string logs;
    for (const std::string& l : d.logs) logs += (logs.empty() ? "" : ",") + l;
    const std::string saved_logs = FLAGS_logs, saved_config = FLAGS_config;
    FLAGS_logs = logs;
    FLAGS_config = d.config;
    FLAGS_out = out + "/" + d.folder;
    const int status = RunDiscover();
    FLAGS_out = out;
    FLAGS_logs = saved_logs;
    FLAGS_config = saved_config;
    if (status != 0) return status;
    DemoDiscovery entry;
    entry.folder = d.folder;
    entry.title = d.title;
    entry.logs = d.logs;
    entry.discovery = json::parse(ReadFile(out + "/" + d.folder + "/discovery.json"));
    summary["discoveries"][d.folder] = {{"added", entry.discovery["added"]},
                                        {"unexplained", entry.discovery["unexplained"]}};
    record.discoveries.push_back(entry);
    record.step_seconds.push_back({std::string("discover: ") + d.folder, SecondsSince(t0)});
  }

  record.total_s = SecondsSince(start);
  summary["seconds"] = record.total_s;
  const std::string markdown = DemoReportMarkdown(record);
  WriteFileAtomically(out + "/report.md", markdown);
  WriteFileAtomically(out + "/report.html", MarkdownToHtml(markdown, "coaxid demo"));
  WriteJson(out + "/summary.json", summary);
  std::fprintf(stderr, "demo: done in %.1f s; open %s/report.html (or read report.md)\n",
               record.total_s, out.c_str());
  return 0;
}

}  // namespace coaxid
