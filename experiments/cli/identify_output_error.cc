#include "experiments/cli/identify_output_error.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <sstream>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/plot.h"
#include "core/report.h"
#include "core/stopwatch.h"
#include "dynamics/vehicle.h"
#include "experiments/cli/cli.h"
#include "experiments/cli/estimation_io.h"
#include "experiments/cli/flag_checks.h"
#include "experiments/cli/flags.h"
#include "experiments/cli/prior_flag.h"
#include "experiments/cli/plausibility_report.h"
#include "ident/noise_weights.h"
#include "ident/baseline/balance_holds.h"
#include "ident/baseline/linear_baseline.h"
#include "ident/ekf/ekf_start.h"
#include "ident/output_error/output_error.h"
#include "ident/residual_outliers.h"

DEFINE_double(segment_s, 1.0,
              "output_error: multiple-shooting segment length and prediction window [s]");
DEFINE_int32(noise_relaxations, 2,
             "output_error: re-estimate the noise from the residuals and refit this many times");
DEFINE_double(huber, 0.0, "output_error: Huber loss threshold in noise std (0: least squares)");
DEFINE_string(noise_std, "",
              "output_error: given output noise std per channel, e.g. phi:0.003,p:0.01,Z:0.02 "
              "(the others are estimated from the data); with --noise_relaxations=0 they are kept");
DEFINE_bool(coloured_residuals, false,
            "output_error: correct the Cramér-Rao std for autocorrelated output residuals "
            "(Morelli & Klein); report.json says which std and by what factor");
DEFINE_string(start, "auto",
              "output_error: starting values: config (then a coarse 0.25 s stage before "
              "--segment_s), linear_kf (the paper's baseline on the balance logs), ekf (one EKF "
              "pass over the first 20 s of the flight logs, then straight at --segment_s), or "
              "auto (ekf when the logs hold a flight log, else config)");

namespace coaxid {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr const char* kOutputErrorUsage =
    "usage: coaxid identify --method=output_error --logs=A.csv[,B.csv] --config=F --out=DIR "
    "[--validate=C.csv] [--holdout_fraction=0.2] [--segment_s=1] "
    "[--start=auto|config|linear_kf|ekf] "
    "[--prior=R.json[:name,...]]";

// Starting values from the paper's linear baseline on the balance logs.
std::string StartFromBaseline(const std::vector<Log>& logs, Vehicle* vehicle) {
  std::vector<BalanceData> balance;
  for (const Log& log : logs) {
    if (log.kind == LogKind::kBalance) balance.push_back(MakeBalanceData(log));
  }
  if (balance.empty()) {
    throw InputError("--start=linear_kf needs at least one balance log in --logs");
  }
  const LinearBaselineResult r = RunLinearBaseline(vehicle->parameters, balance, {}, {});
  auto set = [&](const char* name, double value) {
    const Parameter& p = vehicle->parameters.Get(name);
    if (p.estimated && std::isfinite(value)) {
      vehicle->parameters.SetValue(name, std::clamp(value, p.lower, p.upper));
    }
  };
  set("alpha", r.Parameter(kPsiAlpha).value);
  set("beta", r.Parameter(kThetaBeta).value);
  set("gamma1", r.Parameter(kThetaGamma1).value);
  set("gamma2", r.Parameter(kThetaGamma2).value);
  set("sigma0", r.thrust_map.sigma0);
  return "starting values of alpha, beta, gamma1, gamma2 and sigma0 from the linear_kf baseline "
         "on the balance logs; the others from the config";
}

// Starting values from a short EKF pass (ident/ekf/ekf_start.h); the fit
// then needs no coarse stage. Falls back to the config's values (and the
// coarse-to-fine schedule) when the logs hold no flight log or the pass
// fails, unless --start=ekf asked for it explicitly.
std::string StartFromEkf(const std::vector<EstimationLog>& logs, Vehicle* vehicle,
                         OutputErrorOptions* options) {
  const bool any_flight = std::any_of(logs.begin(), logs.end(), [](const EstimationLog& log) {
    return log.kind == LogKind::kFlight;
  });
  if (!any_flight && FLAGS_start == "auto") return "starting values from the config";
  const EkfStart start = StartFromEkfPass(*vehicle, logs);
  if (!start.usable) {
    if (FLAGS_start == "ekf") throw ComputationError("--start=ekf: " + start.note);
    std::fprintf(stderr, "identify: %s; starting from the config\n", start.note.c_str());
    return start.note + "; starting values from the config";
  }
  std::fprintf(stderr, "identify: %s\n", start.note.c_str());
  vehicle->parameters = start.parameters;
  options->segment_schedule_s = {options->segment_schedule_s.back()};
  char then[64];
  std::snprintf(then, sizeof then, ", then the fit at %g s segments",
                options->segment_schedule_s.back());
  return start.note + then;
}

void PrintEstimates(const OutputErrorResult& result) {
  std::printf("output_error estimates (Cramér-Rao std%s):\n",
              result.coloured_residuals.applied ? ", corrected for coloured residuals" : "");
  for (int k = 0; k < static_cast<int>(result.identifiability.names.size()); ++k) {
    const std::string& name = result.identifiability.names[k];
    const double value = result.parameters.Value(name);
    if (result.identifiability.identifiable[k]) {
      std::printf("  %-22s % .6e +- %.2e\n", name.c_str(), value, result.identifiability.std[k]);
    } else {
      std::printf("  %-22s % .6e   not identifiable from these logs\n", name.c_str(), value);
    }
  }
  std::printf("%s", ScaleTableText(result.gauge, result.parameters, result.ratios).c_str());
  for (const NullDirection& n : result.identifiability.null_directions) {
    std::printf("  note: %s\n", n.explanation.c_str());
  }
}

}  // namespace

nlohmann::json IdentifyOutputError(const IdentifyRun& run) {
  const auto start = Clock::now();
  RequireFlag(run.logs, "logs", kOutputErrorUsage);
  RequireFlag(run.config, "config", kOutputErrorUsage);
  RequireFlag(run.out, "out", kOutputErrorUsage);
  CheckHoldoutFraction(run.holdout_fraction);
  if (FLAGS_start != "auto" && FLAGS_start != "config" && FLAGS_start != "linear_kf" &&
      FLAGS_start != "ekf") {
    throw InputError("--start must be auto, config, linear_kf or ekf, got '" + FLAGS_start + "'");
  }
  CheckOutputFolder(run.out);
  Vehicle vehicle = LoadVehicle(run.config);
  std::vector<Log> logs, validate;
  for (const std::string& path : SplitList(run.logs)) logs.push_back(ReadLog(path));
  for (const std::string& path : SplitList(run.validate)) validate.push_back(ReadLog(path));
  if (logs.empty()) throw InputError("--logs names no file");
  const LogSplit split = SplitEstimationAndValidation(logs, validate, run.holdout_fraction);

  OutputErrorOptions options;
  options.segment_schedule_s = {std::min(0.25, FLAGS_segment_s), FLAGS_segment_s};
  if (FLAGS_segment_s <= 0.25) options.segment_schedule_s = {FLAGS_segment_s};
  options.noise_relaxations = FLAGS_noise_relaxations;
  options.huber_threshold = FLAGS_huber;
  options.coloured_residual_correction = FLAGS_coloured_residuals;
  options.progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  std::string why;
  if (!options.IsValid(&why)) throw InputError("output_error options: " + why);
  if (!FLAGS_noise_std.empty()) {
    options.noise = NoiseFromData(split.estimation);
    for (const std::string& item : SplitList(FLAGS_noise_std)) {
      const size_t colon = item.find(':');
      char* end = nullptr;
      const double value =
          colon == std::string::npos ? NAN : std::strtod(item.c_str() + colon + 1, &end);
      if (colon == std::string::npos || end == item.c_str() + colon + 1 || *end != '\0' ||
          !(value > 0) || !std::isfinite(value)) {
        throw InputError("--noise_std: '" + item + "' is not CHANNEL:STD with STD > 0");
      }
      const std::string channel = item.substr(0, colon);
      if (!options.noise.std.count(channel)) {
        throw InputError("--noise_std: no channel '" + channel + "' in the estimation logs");
      }
      options.noise.std[channel] = value;
    }
  }

  std::vector<std::string> notes = {"Validation data: " + split.description + "."};
  std::string prior_note;
  options.priors = ReadPriorFlag(run.prior, vehicle.parameters, &prior_note);
  if (!prior_note.empty()) notes.push_back(prior_note);
  if (FLAGS_start == "linear_kf") notes.push_back(StartFromBaseline(logs, &vehicle));
  if (FLAGS_start == "ekf" || FLAGS_start == "auto") {
    notes.push_back(StartFromEkf(split.estimation, &vehicle, &options));
  }

  std::fprintf(stderr,
               "identify: output_error on %zu log(s), %zu parameter(s) estimated in the config\n",
               split.estimation.size(), vehicle.parameters.FreeIndices().size());
  OutputErrorResult result = FitOutputError(vehicle, split.estimation, options);
  if (!result.usable && result.scale_move_failed) {
    // The data want a scale member beyond its bounds (with d held, inertias
    // 300x the vehicle's): the model does not describe this vehicle. Fit
    // again with the held member held in the solve too, so that member meets
    // its bound, and report that fit with its plausibility verdict rather
    // than nothing (issue 17).
    std::fprintf(stderr, "identify: %s; fitting again with d held in the solve (the member meets "
                 "its bound: a symptom, see the plausibility verdict)\n",
                 result.why_not_usable.c_str());
    notes.push_back("The first fit needed a scale member beyond its bounds (" +
                    result.why_not_usable + "); this is the fit with d held in the solve, where "
                    "that member meets its bound: the model does not describe this vehicle.");
    // The first fit's converged noise weights, kept: its relaxation solves
    // are not repeated (bounded effort: 44 s of a CoaX flight at 150 Hz,
    // 32.6 s with them, see the README).
    options.scale_free_in_solve = false;
    options.noise = result.noise;
    options.noise_relaxations = 0;
    result = FitOutputError(vehicle, split.estimation, options);
  }
  if (!result.usable) throw ComputationError(result.why_not_usable);
  std::fprintf(stderr, "identify: validating on held-out data ...\n");
  const std::vector<Eigen::MatrixXd> validation_predictions =
      split.validation.empty()
          ? std::vector<Eigen::MatrixXd>{}
          : PredictWithFixedParameters(Vehicle{vehicle.config, result.parameters, vehicle.model},
                                       split.validation, result.noise, FLAGS_segment_s, options);

  if (!result.gauge.note.empty()) notes.push_back(result.gauge.note);
  const std::map<std::string, ChannelOutliers> outliers =
      ResidualOutliers(split.estimation, result.predictions, result.noise);
  const std::string outliers_text = OutliersText(outliers);
  if (!outliers_text.empty()) {
    notes.push_back("Fit " + outliers_text + ".");
    std::fprintf(stderr, "identify: %s\n", outliers_text.c_str());
  }

  std::fprintf(stderr, "identify: validated (elapsed %.1f s); writing plots ...\n",
               SecondsSince(start));
  // Everything is known: only now write.
  const std::string dir = run.out;
  MakeOutputFolder(dir + "/plots");
  nlohmann::json files = nlohmann::json::array(), plots = nlohmann::json::array();
  std::string plot_error;
  std::set<std::string> used;
  auto unique = [&](std::string name) {
    std::string candidate = name;
    for (int n = 2; used.count(candidate); ++n) candidate = name + "_" + std::to_string(n);
    used.insert(candidate);
    return candidate;
  };
  Vehicle estimated = vehicle;
  estimated.parameters = result.parameters;
  WriteFileAtomically(dir + "/config.yaml", estimated.ResolvedConfig());
  files.push_back("config.yaml");
  // One figure per log and part, rendered side by side (many logs make many figures).
  FigureRenderer renderer;
  auto emit = [&](const char* part, const std::vector<EstimationLog>& set,
                  const std::vector<Eigen::MatrixXd>& model) {
    for (size_t i = 0; i < set.size(); ++i) {
      const std::string name = unique(std::string(part) + "_" + set[i].name);
      WriteMeasuredVersusModelCsv(dir + "/" + name + ".csv", set[i], model[i]);
      files.push_back(name + ".csv");
      renderer.Add(MeasuredVersusModelFigure(std::string(part) + ": " + set[i].source, set[i],
                                             model[i]),
                   dir + "/plots/" + name + ".png", "plots/" + name + ".png");
    }
  };
  emit("fit", split.estimation, result.predictions);
  emit("validation", split.validation, validation_predictions);
  for (const std::string& plot : renderer.Finish(&plot_error)) plots.push_back(plot);

  nlohmann::json logs_json = nlohmann::json::array();
  for (const Log& log : logs) logs_json.push_back(log.source);
  nlohmann::json noise = nlohmann::json::object();
  for (const auto& [name, s] : result.noise.std) noise[name] = s;
  nlohmann::json report = {
      {"method", "output_error"},
      {"logs", logs_json},
      {"parameters", ParametersJson(result)},
      {"scale", result.gauge.ToJson()},
      {"ratios", RatiosJson(result.ratios)},
      {"fit", FitJson(ChannelFitErrors(split.estimation, result.predictions))},
      {"residual_outliers", OutliersJson(outliers)},
      {"validation", split.validation.empty()
                         ? nlohmann::json{{"description", split.description},
                                          {"overall_nrmse", nullptr}}
                         : FitJson(ChannelFitErrors(split.validation, validation_predictions))},
      {"prediction_window_s", FLAGS_segment_s},
      {"identifiability", result.identifiability.ToJson()},
      {"coloured_residuals", result.coloured_residuals.ToJson(result.identifiability.names)},
      {"noise_std", noise},
      {"convergence",
       {{"stop_reason", result.hit_iteration_limit
                            ? "iteration limit: the last solve stopped at its " +
                                  std::to_string(options.max_iterations) +
                                  " iterations before converging (" + result.termination + ")"
                            : "converged: " + result.termination},
        {"hit_iteration_limit", result.hit_iteration_limit},
        {"iterations", result.iterations},
        {"initial_cost", result.initial_cost},
        {"final_cost", result.final_cost},
        {"termination", result.termination},
        {"seconds", result.seconds},
        {"timing", result.timing}}},
      {"notes", notes},
      {"outputs", {{"files", files}, {"plots", plots}}}};
  if (!plot_error.empty()) report["outputs"]["plots_skipped"] = plot_error;
  report["validation"]["description"] = split.description;
  const PlausibilityVerdict plausibility =
      AddPlausibility(vehicle.parameters, NoiseFromData(split.estimation).std, &report);
  WriteJson(dir + "/report.json", report);

  if (run.print_estimates) PrintEstimates(result);
  PrintPlausibility(plausibility);
  std::fprintf(stderr, "identify: done in %.1f s -> %s/report.json\n", SecondsSince(start),
               dir.c_str());
  return report;
}

}  // namespace coaxid
