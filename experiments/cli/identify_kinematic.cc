#include "experiments/cli/identify_kinematic.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/plot.h"
#include "core/report.h"
#include "core/report_values.h"
#include "core/stopwatch.h"
#include "core/vehicle_config.h"
#include "experiments/cli/cli.h"
#include "experiments/cli/estimation_io.h"
#include "experiments/cli/flag_checks.h"
#include "experiments/cli/flags.h"
#include "ident/estimation_log.h"
#include "ident/kinematic/flight_path_reconstruction.h"

namespace coaxid {
namespace {

using Clock = std::chrono::steady_clock;

constexpr const char* kUsage =
    "usage: coaxid identify --method=kinematic --logs=A.csv[,B.csv] --out=DIR [--config=F] "
    "[--kinematic_scale_factors=true] [--kinematic_time_offset=true] "
    "[--kinematic_segment_s=0.5]";

// File-name-safe, unique stems of the logs' paths ("flight", "flight_2", ...).
std::vector<std::string> LogNames(const std::vector<std::string>& paths) {
  std::set<std::string> taken;
  std::vector<std::string> names;
  for (const std::string& path : paths) {
    std::string stem = path.substr(path.find_last_of('/') + 1);
    if (stem.size() > 4 && stem.substr(stem.size() - 4) == ".csv") stem.resize(stem.size() - 4);
    for (char& c : stem) {
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
    }
    if (stem.empty()) stem = "log";
    std::string name = stem;
    for (int k = 2; taken.count(name) > 0; ++k) name = stem + "_" + std::to_string(k);
    taken.insert(name);
    names.push_back(name);
  }
  return names;
}

nlohmann::json ReportJson(const KinematicResult& r, const KinematicOptions& options,
                          const std::vector<std::string>& paths, const nlohmann::json& outputs,
                          const std::vector<std::string>& notes) {
  nlohmann::json parameters = nlohmann::json::object();
  const std::vector<std::string>& units = KinematicParameterUnits();
  for (size_t k = 0; k < r.names.size(); ++k) {
    parameters[r.names[k]] = {{"value", r.estimate[k]},
                              {"std", r.std[k]},
                              {"estimated", static_cast<bool>(r.estimated[k])},
                              {"unit", units[k]}};
  }
  nlohmann::json correlation = nlohmann::json::array();
  for (int a = 0; a < r.correlation.rows(); ++a) {
    nlohmann::json row = nlohmann::json::array();
    for (int b = 0; b < r.correlation.cols(); ++b) row.push_back(r.correlation(a, b));
    correlation.push_back(row);
  }
  nlohmann::json noise = nlohmann::json::object();
  for (const auto& [name, s] : r.noise.std) noise[name] = s;
  return {{"method", "kinematic"},
          {"logs", paths},
          {"parameters", parameters},
          {"correlation", {{"names", r.names}, {"matrix", correlation}}},
          {"fit", FitJson(r.fit)},
          {"kinematic",
           {{"model",
             "eqs. 34-42 driven by the measured rates and specific force; rate gyro "
             "p_m = (1 + s_p) p + b_p, accelerometer ax_m = (1 + s_ax) ax + b_ax, positions, "
             "velocities and attitude late by tau"},
            {"segment_s", options.segment_s},
            {"segments", r.num_segments},
            {"unidentified_scale_factors", r.unidentified},
            {"scale_factor_std_limit", options.scale_factor_std_limit},
            {"residual_variance_factor", r.residual_variance_factor},
            {"noise_std", noise},
            {"iterations", r.iterations},
            {"initial_cost", r.initial_cost},
            {"final_cost", r.final_cost},
            {"termination", r.termination},
            {"seconds", r.seconds}}},
          {"outputs", outputs},
          {"notes", notes}};
}

void PrintEstimates(const KinematicResult& r) {
  std::printf("kinematic estimates (sensor errors; std scaled by the residual variance "
              "factor %.3g):\n", r.residual_variance_factor);
  const std::vector<std::string>& units = KinematicParameterUnits();
  for (size_t k = 0; k < r.names.size(); ++k) {
    if (r.estimated[k]) {
      std::printf("  %-5s % .6e +- %.2e %s\n", r.names[k].c_str(), r.estimate[k], r.std[k],
                  units[k].c_str());
    } else {
      std::printf("  %-5s  held at 0\n", r.names[k].c_str());
    }
  }
  std::printf("  fit nrmse:");
  for (const auto& [name, e] : r.fit) std::printf(" %s %.3f", name.c_str(), e.nrmse);
  std::printf("\n");
}

}  // namespace

nlohmann::json IdentifyKinematic(const IdentifyRun& run) {
  const Clock::time_point start = Clock::now();
  RequireFlag(run.logs, "logs", kUsage);
  RequireFlag(run.out, "out", kUsage);
  if (!run.validate.empty()) {
    throw InputError("--validate is for the model-based methods; --method=kinematic "
                     "reconstructs every row of --logs");
  }
  if (!run.prior.empty()) throw InputError("--prior is for output_error and ekf");
  KinematicOptions options;
  options.scale_factors = FLAGS_kinematic_scale_factors;
  options.time_offset = FLAGS_kinematic_time_offset;
  options.segment_s = FLAGS_kinematic_segment_s;
  if (!run.config.empty()) options.gravity = LoadVehicleConfig(run.config).parameters.Value("g");
  std::string why;
  if (!options.IsValid(&why)) throw InputError("--kinematic_*: " + why);
  options.progress = [](const std::string& line) { std::fprintf(stderr, "identify: %s\n", line.c_str()); };
  CheckOutputFolder(run.out);
  const std::vector<std::string> paths = SplitList(run.logs);
  if (paths.empty()) throw InputError("--logs names no file");
  const std::vector<std::string> names = LogNames(paths);

  std::fprintf(stderr, "identify: kinematic: reading %zu log(s)\n", paths.size());
  std::vector<Log> logs;
  std::vector<EstimationLog> estimation;
  for (size_t i = 0; i < paths.size(); ++i) {
    logs.push_back(ReadLog(paths[i]));
    if (logs.back().kind != LogKind::kFlight) {
      throw InputError(paths[i] + ": a " + LogKindName(logs.back().kind) +
                       " log; --method=kinematic reconstructs flight paths from flight logs");
    }
    estimation.push_back(MakeEstimationLog(logs.back()));
    estimation.back().name = names[i];
  }
  const KinematicResult result = ReconstructFlightPath(estimation, options);

  std::vector<std::string> notes;
  notes.push_back("No vehicle model enters: the estimates hold whatever the vehicle. Remove "
                  "the errors with the corrected_*.csv logs before the model-based methods.");
  if (!result.unidentified.empty()) {
    std::string held;
    for (const std::string& n : result.unidentified) held += (held.empty() ? "" : ", ") + n;
    notes.push_back("Not fixed by these logs (std above " +
                    NumberText(options.scale_factor_std_limit, "%g") +
                    " with them free), held at 0: " + held +
                    ". A flight that moves the corresponding rate or specific force fixes them.");
  }
  for (int k = 0; k < static_cast<int>(result.names.size()); ++k) {
    if (result.estimated[k] && result.std[k] > 0 &&
        std::fabs(result.estimate[k]) > 3 * result.std[k]) {
      notes.push_back(result.names[k] + " = " + NumberText(result.estimate[k], "%.4g") + " +- " +
                      NumberText(result.std[k], "%.2g") + " differs from 0 by more than 3 std");
    }
  }

  // Everything is known: only now write.
  MakeOutputFolder(run.out + "/plots");
  nlohmann::json files = nlohmann::json::array();
  for (size_t i = 0; i < logs.size(); ++i) {
    Log corrected = CorrectedLog(logs[i], result);
    corrected.metadata["corrected_from"] = paths[i];
    WriteLog(run.out + "/corrected_" + names[i] + ".csv", corrected);
    files.push_back("corrected_" + names[i] + ".csv");
    WriteMeasuredVersusModelCsv(run.out + "/fit_" + names[i] + ".csv", estimation[i],
                                result.predictions[i]);
    files.push_back("fit_" + names[i] + ".csv");
  }
  std::vector<NamedFigure> figures;
  for (size_t i = 0; i < logs.size(); ++i) {
    figures.push_back({"fit_" + names[i] + ".png",
                       MeasuredVersusModelFigure("kinematic reconstruction, " + names[i],
                                                 estimation[i], result.predictions[i])});
  }
  std::string plot_error;
  nlohmann::json plots = nlohmann::json::array();
  for (const std::string& file : RenderFigures(figures, run.out + "/plots", &plot_error)) {
    plots.push_back("plots/" + file);
  }
  nlohmann::json outputs = {{"files", files}, {"plots", plots}};
  if (!plot_error.empty()) {
    outputs["plots_skipped"] = plot_error;
    notes.push_back("plots skipped: " + plot_error);
  }
  const nlohmann::json report = ReportJson(result, options, paths, outputs, notes);
  WriteJson(run.out + "/report.json", report);
  if (run.print_estimates) PrintEstimates(result);
  std::fprintf(stderr, "identify: kinematic: done in %.2f s -> %s/report.json\n",
               SecondsSince(start), run.out.c_str());
  return report;
}

}  // namespace coaxid
