#include "experiments/cli/identify_ekf.h"

#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <set>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/plot.h"
#include "core/report.h"
#include "core/report_values.h"
#include "core/stopwatch.h"
#include "dynamics/vehicle.h"
#include "experiments/cli/cli.h"
#include "experiments/cli/estimation_io.h"
#include "experiments/cli/flag_checks.h"
#include "experiments/cli/flags.h"
#include "experiments/cli/prior_flag.h"
#include "experiments/cli/plausibility_report.h"
#include "ident/ekf/ekf.h"
#include "ident/ekf/history_files.h"
#include "ident/ekf/report.h"
#include "ident/ekf/states_at_rows.h"
#include "ident/estimation_log.h"
#include "ident/ekf/process_noise_from_data.h"
#include "ident/noise_weights.h"
#include "ident/output_error/output_error.h"  // ChannelFitErrors

namespace coaxid {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr const char* kUsage =
    "usage: coaxid identify --method=ekf --logs=A.csv[,B.csv] --config=F --out=DIR "
    "[--validate=C.csv] [--holdout_fraction=0.2] [--smoother=true] "
    "[--ekf_scale_anchor=d|none] [--ekf_transition=linearised|sensitivities] "
    "[--ekf_covariance_pass=true] [--ekf_refinements=10] [--ekf_process_noise=1] "
    "[--ekf_process_noise_from_data=true] [--ekf_window_s=1] "
    "[--ekf_noise_adaptations=1] [--ekf_noise_adaptation_rows=120000] [--ekf_gate=1e-6] [--ekf_initial_report=R.json] "
    "[--prior=R.json[:name,...]]";

std::vector<Log> ReadFlightLogs(const std::vector<std::string>& paths, const char* flag) {
  std::vector<Log> logs;
  for (const std::string& path : paths) {
    Log log = ReadLog(path);
    if (log.kind != LogKind::kFlight) {
      throw InputError(path + ": a " + LogKindName(log.kind) + " log given to --" + flag +
                       ", but --method=ekf estimates from flight logs (states and parameters "
                       "together); balance logs are for linear_kf and output_error");
    }
    logs.push_back(std::move(log));
  }
  return logs;
}

// File-name-safe, unique names for the data sets.
void MakeNamesUnique(std::vector<EstimationLog>* logs, std::set<std::string>* taken) {
  for (EstimationLog& log : *logs) {
    std::string stem = log.name.empty() ? "log" : log.name;
    for (char& c : stem) {
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
    }
    std::string name = stem;
    for (int k = 2; taken->count(name) > 0; ++k) name = stem + "_" + std::to_string(k);
    taken->insert(name);
    log.name = name;
  }
}

// Initial values and std from an earlier report.json.
std::string ApplyInitialReport(const std::string& path, Vehicle* vehicle, EkfOptions* options) {
  int used = 0;
  for (const ReportedParameter& r : ReadReportedParameters(path)) {
    const int i = vehicle->parameters.Index(r.name);
    if (i < 0 || !vehicle->parameters[i].estimated) continue;
    CheckWithinConfigBounds(path, r, vehicle->parameters[i]);
    vehicle->parameters.SetValue(r.name, r.value);
    if (std::isfinite(r.std) && r.std > 0) options->initial_parameter_std_by_name[r.name] = r.std;
    ++used;
  }
  if (used == 0) throw InputError(path + ": no value for any free parameter of the config");
  return "initial values (and std where given) of " + std::to_string(used) +
         " free parameters from " + path +
         " (if that report was estimated from these same logs, the data count twice)";
}

void PrintEstimates(const EkfResult& r) {
  std::printf("ekf estimates (std from the %s):\n",
              r.covariance_pass ? "covariance pass at the estimates" : "filter");
  if (r.refinements > 0 || !r.refinement_converged) {
    std::printf("  (%d Gauss-Newton refinement(s) of the filter's likelihood: largest step "
                "%.2g std from the estimation pass, %.2g std from these)\n",
                r.refinements, r.step_std_at_pass1, r.step_std_at_estimate);
  }
  if (!r.refinement_converged) {
    std::printf("  SHORT OF THE MAXIMUM of the filter's likelihood (%s): a further step would "
                "move %s; these std do not hold. Judge them with output_error (or start the EKF "
                "from its estimates).\n",
                r.refinement_stop.c_str(), r.short_of_maximum.c_str());
  }
  for (size_t k = 0; k < r.free_names.size(); ++k) {
    if (r.identifiable[k]) {
      std::printf("  %-10s % .6e +- %.2e\n", r.free_names[k].c_str(), r.estimate[k],
                  r.estimate_std[k]);
    } else {
      std::printf("  %-10s % .6e  (not separately identifiable)\n", r.free_names[k].c_str(),
                  r.estimate[k]);
    }
  }
  std::printf("%s", ScaleTableText(r.gauge, r.parameters, r.ratios).c_str());
  std::printf("  NIS per degree of freedom %.4f (95 %% band %.4f .. %.4f)%s\n", r.total_nis.mean,
              r.total_nis.lower, r.total_nis.upper,
              r.total_nis.consistent() ? "" : "  OUTSIDE the band");
}

}  // namespace

nlohmann::json IdentifyEkf(const IdentifyRun& run) {
  const Clock::time_point start = Clock::now();
  RequireFlag(run.logs, "logs", kUsage);
  RequireFlag(run.config, "config", kUsage);
  RequireFlag(run.out, "out", kUsage);
  CheckHoldoutFraction(run.holdout_fraction);
  if (!(FLAGS_ekf_window_s > 0 && std::isfinite(FLAGS_ekf_window_s))) {
    throw InputError("--ekf_window_s must be > 0, got " + std::to_string(FLAGS_ekf_window_s));
  }
  if (!(FLAGS_ekf_process_noise > 0 && std::isfinite(FLAGS_ekf_process_noise))) {
    throw InputError("--ekf_process_noise must be > 0, got " +
                     std::to_string(FLAGS_ekf_process_noise));
  }
  EkfOptions options;
  options.smoother = FLAGS_smoother;
  options.covariance_pass = FLAGS_ekf_covariance_pass;
  if (FLAGS_ekf_refinements < 0) {
    throw InputError("--ekf_refinements must be >= 0, got " +
                     std::to_string(FLAGS_ekf_refinements));
  }
  options.max_refinements = FLAGS_ekf_refinements;
  if (FLAGS_ekf_scale_anchor == "d") {
    options.scale_anchor = EkfOptions::ScaleAnchor::kHubDistance;
  } else if (FLAGS_ekf_scale_anchor == "none") {
    options.scale_anchor = EkfOptions::ScaleAnchor::kNone;
  } else {
    throw InputError("--ekf_scale_anchor must be d or none, got '" + FLAGS_ekf_scale_anchor + "'");
  }
  if (FLAGS_ekf_transition == "linearised" || FLAGS_ekf_transition == "linearized") {
    options.transition = EkfTransitionMethod::kLinearised;
  } else if (FLAGS_ekf_transition == "sensitivities") {
    options.transition = EkfTransitionMethod::kSensitivities;
  } else {
    throw InputError("--ekf_transition must be linearised or sensitivities, got '" +
                     FLAGS_ekf_transition + "'");
  }
  for (double& q : options.state_psd) q *= FLAGS_ekf_process_noise;
  options.effect_state_psd *= FLAGS_ekf_process_noise;
  if (FLAGS_ekf_noise_adaptations < 0 || FLAGS_ekf_noise_adaptations > 5) {
    throw InputError("--ekf_noise_adaptations must lie in 0 .. 5, got " +
                     std::to_string(FLAGS_ekf_noise_adaptations));
  }
  options.noise_adaptations = FLAGS_ekf_noise_adaptations;
  if (FLAGS_ekf_noise_adaptation_rows < 0) {
    throw InputError("--ekf_noise_adaptation_rows must be >= 0 (0: every row), got " +
                     std::to_string(FLAGS_ekf_noise_adaptation_rows));
  }
  options.noise_adaptation_rows = FLAGS_ekf_noise_adaptation_rows;
  if (!(FLAGS_ekf_gate >= 0 && FLAGS_ekf_gate < 1)) {
    throw InputError("--ekf_gate must lie in [0, 1) (0: no innovation gate), got " +
                     NumberText(FLAGS_ekf_gate, "%g"));
  }
  options.gate_probability = FLAGS_ekf_gate;
  CheckOutputFolder(run.out);
  const std::vector<std::string> paths = SplitList(run.logs);
  const std::vector<std::string> validate_paths = SplitList(run.validate);
  if (paths.empty()) throw InputError("--logs names no file");

  Vehicle vehicle = LoadVehicle(run.config);
  EkfReportContext context;
  if (!FLAGS_ekf_initial_report.empty()) {
    context.notes.push_back(ApplyInitialReport(FLAGS_ekf_initial_report, &vehicle, &options));
  }
  // --prior: initial value and covariance (a prior on d fixes the scale).
  std::string prior_note;
  for (const ParameterPrior& prior : ReadPriorFlag(run.prior, vehicle.parameters, &prior_note)) {
    vehicle.parameters.SetValue(prior.name, prior.value);
    options.initial_parameter_std_by_name[prior.name] = prior.std;
  }
  if (!prior_note.empty()) context.notes.push_back(prior_note);
  const ParameterSet initial = vehicle.parameters;
  std::fprintf(stderr, "identify: ekf: reading %zu log(s)%s\n", paths.size(),
               validate_paths.empty() ? "" : " and the validation logs");
  // Estimation and validation data (experiments/cli/estimation_io.h); the
  // logs as read are not kept (a long log's columns are 160 B a row).
  LogSplit split = SplitEstimationAndValidation(ReadFlightLogs(paths, "logs"),
                                                ReadFlightLogs(validate_paths, "validate"),
                                                run.holdout_fraction);
  std::vector<EstimationLog>& estimation = split.estimation;
  std::vector<EstimationLog>& validation = split.validation;
  context.validation_description = split.description;
  std::set<std::string> taken;
  MakeNamesUnique(&estimation, &taken);
  if (!validate_paths.empty()) {
    MakeNamesUnique(&validation, &taken);
  } else {
    for (size_t i = 0; i < validation.size(); ++i) validation[i].name = estimation[i].name;
  }
  context.logs = paths;
  context.validation_logs = validate_paths;
  context.window_s = FLAGS_ekf_window_s;

  // Measurement noise from the data (ident/noise_weights.h); validation
  // channels the estimation data lack get theirs from the validation data.
  context.noise = NoiseFromData(estimation);
  context.noise_source =
      "first differences of each channel over the estimation data, std(diff) / sqrt(2) "
      "(ident/noise_weights.h NoiseFromData): an upper bound where the signal moves fast "
      "between samples";
  NoiseWeights validation_noise = context.noise;
  if (!validation.empty()) {
    for (const auto& [name, s] : NoiseFromData(validation).std) {
      validation_noise.std.emplace(name, s);
    }
  }

  long last_report = -1;
  const Clock::time_point filter_start = Clock::now();
  options.progress = [&](long done, long total) {
    if (done == last_report) return;
    last_report = done;
    // Rows of every pass (noise adaptations, estimation, covariance) in
    // total, so the ETA holds for the whole run.
    const double elapsed = SecondsSince(filter_start);
    const double rate = done / std::max(elapsed, 1e-9);
    std::fprintf(stderr,
                 "identify: ekf: %ld / %ld rows (%.0f %%), %.2f s, %.0f rows/s, about %.0f s left\n",
                 done, total, 100.0 * done / std::max(1L, total), elapsed, rate,
                 (total - done) / std::max(rate, 1e-9));
  };
  std::fprintf(stderr, "identify: ekf on %zu log part(s), %zu free parameter(s): %d noise "
               "adaptation pass(es), estimation pass%s ...\n",
               estimation.size(), vehicle.parameters.FreeIndices().size(),
               options.noise_adaptations, options.covariance_pass ? ", covariance pass" : "");
  // The per-row records stream to scratch files (ident/ekf/history_files.h):
  // memory independent of the log length; the states are kept at the fit
  // windows' first rows only.
  std::vector<std::vector<int>> window_starts;
  for (const EstimationLog& log : estimation) {
    window_starts.push_back(WindowStartRows(log, FLAGS_ekf_window_s));
  }
  // Process noise from the data (ident/ekf/process_noise_from_data.h): the
  // probe over the first 20 s gives the starting scale; a run that still
  // loses the filter later in the log is repeated with the PSDs raised
  // tenfold, at most six times in all.
  nlohmann::json process_noise_from_data;
  ProcessNoiseFromData probe;
  if (FLAGS_ekf_process_noise_from_data) {
    probe = ProbeProcessNoise(vehicle, estimation, context.noise, options);
    std::fprintf(stderr, "identify: ekf: %s\n", probe.note.c_str());
  }
  const auto say = [](const std::string& line) {
    std::fprintf(stderr, "identify: ekf: %s; running again\n", line.c_str());
  };
  std::unique_ptr<EkfHistoryFiles> history;
  const EkfResult result = RunRaisingProcessNoise(
      options, &probe,
      [&](const EkfOptions& o) {
        history = std::make_unique<EkfHistoryFiles>(
            estimation, vehicle.model.StateNames(), o.smoother,
            fs::temp_directory_path().string(), window_starts);
        return RunEkf(vehicle, estimation, context.noise, o, history.get());
      },
      say, FLAGS_ekf_process_noise_from_data ? 6 : 0);
  const EkfOptions unraised = options;
  options = WithRaisedProcessNoise(unraised, probe.scale);
  if (FLAGS_ekf_process_noise_from_data) {
    context.notes.push_back(probe.note + ".");
    process_noise_from_data = probe.ToJson();
  }
  if (!result.usable) {
    throw ComputationError(result.failure +
                           (FLAGS_ekf_process_noise_from_data
                                ? " (with the velocity and rate process noise at " +
                                      NumberText(probe.scale, "%g") +
                                      " x the default, after raising it from the data; "
                                      "--ekf_process_noise multiplies it further)"
                                : std::string()));
  }
  std::fprintf(stderr, "identify: ekf: done in %.2f s (propagation %.2f s, updates %.2f s, "
               "smoother %.2f s)\n", result.total_s, result.propagation_s, result.update_s,
               result.smoother_s);

  // Fit: window predictions from the reported (smoothed) states.
  Vehicle estimated = vehicle;
  estimated.parameters = result.parameters;
  const bool smoothed = options.smoother;
  context.fit_states = std::string(smoothed ? "smoothed" : "filtered") + " states" +
                       (result.covariance_pass ? " of the covariance pass" : "");
  std::vector<Eigen::MatrixXd> fit_predictions;
  for (size_t i = 0; i < estimation.size(); ++i) {
    fit_predictions.push_back(WindowPredictions(
        estimated, estimation[i], history->states_at_rows().Reported(static_cast<int>(i), smoothed),
        FLAGS_ekf_window_s, options.integrator, &context.failed_fit_windows));
  }
  context.fit = ChannelFitErrors(estimation, fit_predictions);

  // Validation: the filter with every parameter fixed, then the same windows.
  std::vector<Eigen::MatrixXd> validation_predictions;
  if (!validation.empty()) {
    Vehicle fixed = estimated;
    for (int i = 0; i < fixed.parameters.size(); ++i) {
      fixed.parameters.mutable_parameter(i).estimated = false;
    }
    EkfOptions state_only = unraised;
    state_only.progress = nullptr;
    state_only.noise_adaptations = 0;
    for (const auto& [name, s] : result.noise.std) validation_noise.std[name] = s;
    std::fprintf(stderr, "identify: ekf: state estimation on the validation data ...\n");
    std::vector<std::vector<int>> validation_starts;
    for (const EstimationLog& log : validation) {
      validation_starts.push_back(WindowStartRows(log, FLAGS_ekf_window_s));
    }
    // At the estimation's process noise, raised further if the model
    // with the estimates loses the held-out data.
    std::unique_ptr<EkfStatesAtRows> states;
    ProcessNoiseFromData validation_probe;
    validation_probe.scale = probe.scale;
    const EkfResult v = RunRaisingProcessNoise(
        state_only, &validation_probe,
        [&](const EkfOptions& o) {
          states = std::make_unique<EkfStatesAtRows>(validation_starts);
          return RunEkf(fixed, validation, validation_noise, o, states.get());
        },
        say, FLAGS_ekf_process_noise_from_data ? 6 : 0);
    if (!v.usable) throw ComputationError("validation: " + v.failure);
    if (validation_probe.scale > probe.scale) {
      context.notes.push_back("Validation: " + validation_probe.note + ".");
    }
    const EkfStatesAtRows& validation_states = *states;
    for (size_t i = 0; i < validation.size(); ++i) {
      validation_predictions.push_back(WindowPredictions(
          estimated, validation[i], validation_states.Reported(static_cast<int>(i), smoothed),
          FLAGS_ekf_window_s, options.integrator, &context.failed_validation_windows));
    }
    context.validation = ChannelFitErrors(validation, validation_predictions);
  }
  if (context.failed_fit_windows + context.failed_validation_windows > 0) {
    context.notes.push_back(std::to_string(context.failed_fit_windows +
                                           context.failed_validation_windows) +
                            " prediction window(s) could not be simulated (left out of fit / "
                            "validation)");
  }

  // Everything is known: only now write.
  const std::string dir = run.out;
  MakeOutputFolder(dir + "/plots");
  nlohmann::json files = nlohmann::json::array();
  auto write = [&](const std::string& name, const std::string& text) {
    WriteFileAtomically(dir + "/" + name, text);
    files.push_back(name);
  };
  write("config.yaml", vehicle.ResolvedConfig());
  write("estimated_config.yaml", estimated.ResolvedConfig());
  auto write_table = [&](const std::string& name,
                         const std::function<void(const EmitText&)>& table) {
    WriteFileAtomically(dir + "/" + name, table);
    files.push_back(name);
  };
  write_table("states.csv", [&](const EmitText& emit) { history->StatesCsv(emit); });
  write_table("parameters.csv", [&](const EmitText& emit) {
    history->ParametersCsv(result.free_names, result.covariance_pass, emit);
  });
  write_table("innovations.csv", [&](const EmitText& emit) { history->InnovationsCsv(emit); });
  for (size_t i = 0; i < estimation.size(); ++i) {
    WriteMeasuredVersusModelCsv(dir + "/fit_" + estimation[i].name + ".csv", estimation[i],
                                fit_predictions[i]);
    files.push_back("fit_" + estimation[i].name + ".csv");
  }
  for (size_t i = 0; i < validation.size(); ++i) {
    WriteMeasuredVersusModelCsv(dir + "/validation_" + validation[i].name + ".csv",
                                validation[i], validation_predictions[i]);
    files.push_back("validation_" + validation[i].name + ".csv");
  }
  std::fprintf(stderr, "identify: ekf: plotting (gnuplot) ...\n");
  nlohmann::json plots = nlohmann::json::array();
  std::string plot_error;
  // The plots from the thinned copy (at most ~3000 rows a log, as they draw).
  EkfResult thinned = result;
  thinned.logs = history->thinned();
  std::vector<Eigen::MatrixXd> thinned_fit;
  for (size_t i = 0; i < fit_predictions.size(); ++i) {
    const std::vector<int>& rows = thinned.logs[i].rows;
    thinned_fit.emplace_back(rows.size(), fit_predictions[i].cols());
    for (size_t k = 0; k < rows.size(); ++k) {
      thinned_fit[i].row(k) = fit_predictions[i].row(rows[k]);
    }
  }
  for (const std::string& file :
       RenderFigures(EkfFigures(thinned, thinned_fit), dir + "/plots", &plot_error)) {
    plots.push_back("plots/" + file);
  }
  context.outputs = {{"files", files}, {"plots", plots}};
  if (!plot_error.empty()) {
    context.outputs["plots_skipped"] = plot_error;
    context.notes.push_back("plots skipped: " + plot_error);
  }
  context.notes.push_back("Validation data: " + context.validation_description + ".");
  nlohmann::json report = EkfReportJson(result, options, initial, context);
  if (!process_noise_from_data.is_null()) {
    report["ekf"]["process_noise"]["from_data"] = process_noise_from_data;
  }
  // context.noise: the sensor noise from the data (NoiseFromData above).
  const PlausibilityVerdict plausibility =
      AddPlausibility(vehicle.parameters, context.noise.std, &report);
  WriteJson(dir + "/report.json", report);
  if (run.print_estimates) PrintEstimates(result);
  PrintPlausibility(plausibility);
  std::fprintf(stderr, "identify: ekf: done in %.2f s -> %s/report.json%s\n", SecondsSince(start),
               dir.c_str(), plot_error.empty() ? "" : " (plots skipped)");
  return report;
}

}  // namespace coaxid
