#include "experiments/cli/compare.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/log.h"
#include "core/plot.h"
#include "core/report.h"
#include "core/report_values.h"
#include "core/stopwatch.h"
#include "core/vehicle_config.h"
#include "experiments/cli/cli.h"
#include "experiments/cli/flag_checks.h"
#include "experiments/cli/flags.h"
#include "experiments/cli/identify.h"
#include "experiments/reports/compare_table.h"

namespace coaxid {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr const char* kCompareUsage =
    "usage: coaxid compare --logs=A.csv[,B.csv...] --config=F --out=DIR [--validate=C.csv,...] "
    "[--holdout_fraction=0.2] [--truth=T.json] [--prior=R.json[:name,...]]";

// The paths of the given logs, balance and flight apart. Reads (and so
// checks) every log.
void SortLogs(const std::vector<std::string>& paths, std::vector<std::string>* balance,
              std::vector<std::string>* flight) {
  for (const std::string& path : paths) {
    (ReadLog(path).kind == LogKind::kBalance ? balance : flight)->push_back(path);
  }
}

json ReadTruth(const std::string& path) {
  if (path.empty()) return nullptr;
  json truth;
  try {
    truth = json::parse(ReadFile(path));
  } catch (const json::exception& e) {
    throw InputError(path + ": not a JSON document (" + e.what() + ")");
  }
  if (!truth.is_object() || !truth.contains("parameters") || !truth["parameters"].is_object()) {
    throw InputError(path + ": no \"parameters\" object (truth.json of cli-and-reports.md)");
  }
  for (const auto& [name, value] : truth["parameters"].items()) {
    if (!value.is_number()) {
      throw InputError(path + ": parameters." + name + " is not a number");
    }
  }
  return truth["parameters"];
}

// A folder next to out for the runs until everything succeeded.
fs::path StagingFolder(const std::string& out) {
  fs::path target = fs::path(out).lexically_normal();
  if (target.filename().empty()) target = target.parent_path();
  const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  return parent /
         ("." + target.filename().string() + ".compare-partial-" + std::to_string(::getpid()));
}

// Moves everything in staging into out (replacing what is there), then
// removes staging.
void Publish(const fs::path& staging, const std::string& out) {
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec || !fs::is_directory(out)) {
    throw InputError("cannot create output folder '" + out + "': " + ec.message());
  }
  for (const fs::directory_entry& entry : fs::directory_iterator(staging)) {
    const fs::path target = fs::path(out) / entry.path().filename();
    fs::remove_all(target);
    fs::rename(entry.path(), target);
  }
  fs::remove_all(staging);
}

}  // namespace

json Compare(const CompareRequest& request) {
  const Clock::time_point start = Clock::now();
  RequireFlag(request.logs, "logs", kCompareUsage);
  RequireFlag(request.config, "config", kCompareUsage);
  RequireFlag(request.out, "out", kCompareUsage);
  CheckHoldoutFraction(request.holdout_fraction);
  CheckOutputFolder(request.out);
  // Every input is read and checked before any method runs.
  LoadVehicleConfig(request.config);
  const std::vector<std::string> paths = SplitList(request.logs);
  if (paths.empty()) throw InputError("--logs names no file");
  std::vector<std::string> balance, flight, validate_balance, validate_flight;
  SortLogs(paths, &balance, &flight);
  SortLogs(SplitList(request.validate), &validate_balance, &validate_flight);
  const json truth = ReadTruth(request.truth);

  std::vector<MethodRun> runs(3);
  runs[0].method = "linear_kf";
  runs[0].logs = balance;
  runs[0].validate = validate_balance;
  if (balance.empty()) {
    runs[0].reason = "no balance log in --logs (linear_kf is the paper's static balance method)";
  }
  runs[1].method = "output_error";
  runs[1].logs = paths;
  runs[1].validate = SplitList(request.validate);
  runs[2].method = "ekf";
  runs[2].logs = flight;
  runs[2].validate = validate_flight;
  if (flight.empty()) {
    runs[2].reason =
        "no flight log in --logs (the EKF estimates states and parameters from "
        "flight logs)";
  }

  const fs::path staging = StagingFolder(request.out);
  fs::remove_all(staging);
  json comparison;
  std::string markdown;
  std::error_code ec;
  try {
    fs::create_directories(staging / "plots", ec);
    if (ec) throw InputError("cannot create '" + staging.string() + "': " + ec.message());
    int done = 0;
    for (MethodRun& run : runs) {
      if (!run.reason.empty()) {
        std::fprintf(stderr, "compare: %s skipped: %s\n", run.method.c_str(), run.reason.c_str());
        continue;
      }
      std::fprintf(stderr, "compare: [%d/3] %s on %zu log(s) (elapsed %.1f s) ...\n", ++done,
                   run.method.c_str(), run.logs.size(), SecondsSince(start));
      IdentifyRun identify;
      identify.method = run.method;
      identify.logs = Joined(run.logs, ",");
      identify.validate = Joined(run.validate, ",");
      identify.config = request.config;
      identify.out = (staging / run.method).string();
      identify.holdout_fraction = request.holdout_fraction;
      identify.print_estimates = false;
      if (run.method != "linear_kf") identify.prior = request.prior;
      const MethodRun& oe = runs[1];
      if (run.method == "ekf" && request.prior.empty() && !balance.empty() &&
          oe.status == "ran") {
        // The balance fit's scale (model.md decision 8).
        identify.prior = (staging / oe.folder / "report.json").string() + ":d";
        run.prior = "d from output_error (balance + flight logs fix the scale)";
      }
      run.folder = run.method;
      const Clock::time_point t0 = Clock::now();
      try {
        run.report = Identify(identify);
        run.status = "ran";
      } catch (const ComputationError& e) {
        run.status = "failed";
        run.reason = e.what();
        std::fprintf(stderr, "compare: %s failed: %s\n", run.method.c_str(), e.what());
      } catch (const InputError& e) {
        throw InputError(run.method + ": " + e.what());
      }
      run.wall_s = SecondsSince(t0);
      std::fprintf(stderr, "compare: %s %s in %.2f s\n", run.method.c_str(), run.status.c_str(),
                   run.wall_s);
    }
    bool any_ran = false;
    std::string why;
    for (const MethodRun& run : runs) {
      any_ran = any_ran || run.status == "ran";
      why += "; " + run.method + ": " + run.reason;
    }
    if (!any_ran) throw ComputationError("no method gave estimates" + why);

    comparison = ComparisonJson(runs, truth);
    comparison["logs"] = paths;
    comparison["validate"] = SplitList(request.validate);
    comparison["config"] = request.config;
    comparison["truth"] = request.truth.empty() ? json(nullptr) : json(request.truth);
    comparison["holdout_fraction"] = request.holdout_fraction;
    std::string plot_error;
    std::string plot = "plots/estimates.png";
    if (!RenderFigure(EstimatesFigure(comparison), (staging / plot).string(), &plot_error)) {
      plot.clear();
      comparison["plots_skipped"] = plot_error;
    }
    comparison["plots"] = plot.empty() ? json::array() : json::array({plot});
    markdown = ComparisonMarkdown(comparison, plot);
    if (!plot_error.empty()) markdown += "\nPlots skipped: " + plot_error + "\n";
    WriteJson((staging / "compare.json").string(), comparison);
    WriteFileAtomically((staging / "compare.md").string(), markdown);
    Publish(staging, request.out);
  } catch (...) {
    fs::remove_all(staging, ec);
    throw;
  }
  if (request.print_table) std::cout << markdown;
  std::fprintf(stderr, "compare: done in %.1f s -> %s/compare.md\n", SecondsSince(start),
               request.out.c_str());
  return comparison;
}

int RunCompare() {
  const IdentifyRun flags = IdentifyRunFromFlags();
  Compare({flags.logs, flags.validate, flags.config, flags.out, FLAGS_truth,
           flags.holdout_fraction, flags.prior});
  return 0;
}

}  // namespace coaxid
