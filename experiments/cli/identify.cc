#include "experiments/cli/identify.h"

#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/plot.h"
#include "core/report.h"
#include "core/stopwatch.h"
#include "dynamics/vehicle.h"
#include "experiments/cli/cli.h"
#include "experiments/cli/flag_checks.h"
#include "experiments/cli/flags.h"
#include "experiments/cli/identify_ekf.h"
#include "experiments/cli/identify_kinematic.h"
#include "experiments/cli/identify_output_error.h"
#include "experiments/cli/plausibility_report.h"
#include "ident/baseline/linear_baseline.h"
#include "ident/baseline/plots.h"
#include "ident/baseline/report.h"

namespace coaxid {
namespace {

namespace fs = std::filesystem;

constexpr const char* kLinearKfUsage =
    "usage: coaxid identify --method=linear_kf --logs=A.csv[,B.csv] --config=F --out=DIR "
    "[--validate=C.csv] [--holdout_fraction=0.2] [--process_noise=0]";

void CheckMethod(const std::string& method) {
  if (method == "linear_kf" || method == "output_error" || method == "ekf" ||
      method == "kinematic") {
    return;
  }
  throw InputError("unknown method '" + method +
                   "' (the methods are linear_kf, ekf, output_error and kinematic)");
}

// Reads logs; linear_kf takes balance logs only.
std::vector<Log> ReadBalanceLogs(const std::vector<std::string>& paths, const char* flag) {
  std::vector<Log> logs;
  for (const std::string& path : paths) {
    Log log = ReadLog(path);
    if (log.kind != LogKind::kBalance) {
      throw InputError(path + ": a " + LogKindName(log.kind) + " log given to --" + flag +
                       ", but --method=linear_kf estimates from balance logs only (the "
                       "paper's static experiment, sect. 3-4); flight logs are for the ekf "
                       "and output_error methods");
    }
    logs.push_back(std::move(log));
  }
  return logs;
}

// File-name-safe, unique names for the data sets ("balance", "balance_2", ...).
std::vector<std::string> UniqueNames(const std::vector<std::string>& stems,
                                     std::set<std::string>* taken) {
  std::vector<std::string> out;
  for (std::string stem : stems) {
    for (char& c : stem) {
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
    }
    std::string name = stem;
    for (int k = 2; taken->count(name) > 0; ++k) name = stem + "_" + std::to_string(k);
    taken->insert(name);
    out.push_back(name);
  }
  return out;
}

std::string Number(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", v);
  return buffer;
}

std::string Percent(double fraction) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.1f %%", 100 * fraction);
  return buffer;
}

void PrintEstimates(const LinearBaselineResult& r) {
  std::printf("linear_kf estimates (std includes the thrust map's uncertainty):\n");
  auto line = [](const char* name, double value, double std, const char* note) {
    std::printf("  %-9s % .6e +- %.2e  %s\n", name, value, std, note);
  };
  for (int i = 0; i < kNumTheta; ++i) {
    const BaselineEstimate e = r.Parameter(i);
    line(ThetaName(i), e.value, e.std, "Kalman filter");
  }
  const BaselineEstimate alpha = r.Parameter(kPsiAlpha);
  line("alpha", alpha.value, alpha.std, "thrust map");
  line("sigma0", r.thrust_map.sigma0, r.thrust_map.sigma0_std, "sigma map fit");
  line("Cz", r.Cz_from_beta.value, r.Cz_from_beta.std, "Cz_beta / beta");
  line("Cz'", r.Cz_from_alpha.value, r.Cz_from_alpha.std,
       r.Cz_disagree ? "Cz_alpha / alpha: DISAGREES with Cz_beta / beta" : "Cz_alpha / alpha");
  std::printf("  fit nrmse:");
  for (int c = 0; c < kNumLoadChannels; ++c) {
    if (r.fit[c].error.count > 0) std::printf(" %s %.3f", LoadChannelName(c), r.fit[c].error.nrmse);
  }
  std::printf("\n  validation nrmse:");
  for (int c = 0; c < kNumLoadChannels; ++c) {
    if (r.validation_fit[c].error.count > 0) {
      std::printf(" %s %.3f", LoadChannelName(c), r.validation_fit[c].error.nrmse);
    }
  }
  std::printf("\n");
}

}  // namespace

int RunIdentify() {
  Identify(IdentifyRunFromFlags());
  return 0;
}

IdentifyRun IdentifyRunFromFlags() {
  IdentifyRun run;
  run.method = FLAGS_method;
  run.logs = FLAGS_logs;
  run.validate = FLAGS_validate;
  run.config = FLAGS_config;
  run.out = FLAGS_out;
  run.holdout_fraction = FLAGS_holdout_fraction;
  run.prior = FLAGS_prior;
  return run;
}

nlohmann::json Identify(const IdentifyRun& run) {
  RequireFlag(run.method, "method", kLinearKfUsage);
  CheckMethod(run.method);
  if (run.method == "output_error") return IdentifyOutputError(run);
  if (run.method == "ekf") return IdentifyEkf(run);
  if (run.method == "kinematic") return IdentifyKinematic(run);
  if (!run.prior.empty()) {
    throw InputError("--prior is for output_error and ekf; linear_kf takes d from the config "
                     "(model.md decision 6)");
  }
  return IdentifyLinearKf(run);
}

nlohmann::json IdentifyLinearKf(const IdentifyRun& run) {
  const auto start = std::chrono::steady_clock::now();
  RequireFlag(run.logs, "logs", kLinearKfUsage);
  RequireFlag(run.config, "config", kLinearKfUsage);
  RequireFlag(run.out, "out", kLinearKfUsage);
  CheckHoldoutFraction(run.holdout_fraction);
  if (!(FLAGS_process_noise >= 0 && std::isfinite(FLAGS_process_noise))) {
    throw InputError("--process_noise must be finite and >= 0, got " + Number(FLAGS_process_noise));
  }
  CheckOutputFolder(run.out);
  const std::vector<std::string> paths = SplitList(run.logs);
  const std::vector<std::string> validate_paths = SplitList(run.validate);
  if (paths.empty()) throw InputError("--logs names no file");

  const Vehicle vehicle = LoadVehicle(run.config);
  std::fprintf(stderr, "identify: reading %zu log(s)%s\n", paths.size(),
               validate_paths.empty() ? "" : " and the validation logs");
  const std::vector<Log> logs = ReadBalanceLogs(paths, "logs");
  const std::vector<Log> validate_logs = ReadBalanceLogs(validate_paths, "validate");

  // Estimation and validation data: --validate logs, or the final part of each log.
  std::vector<BalanceData> estimation, validation;
  std::string validation_description;
  BaselineReportContext context;
  context.logs = paths;
  context.validation_logs = validate_paths;
  if (!validate_paths.empty()) {
    for (const Log& log : logs) estimation.push_back(MakeBalanceData(log));
    for (const Log& log : validate_logs) validation.push_back(MakeBalanceData(log));
    validation_description = "the --validate logs, whole";
  } else if (run.holdout_fraction > 0) {
    validation_description =
        "held out (contiguous final part of each log, cut at a hold "
        "boundary, --holdout_fraction=" +
        Number(run.holdout_fraction) + "):";
    for (const Log& log : logs) {
      const int cut = HoldoutStartRow(log, run.holdout_fraction);
      estimation.push_back(MakeBalanceData(log, 0, cut));
      validation.push_back(MakeBalanceData(log, cut));
      validation_description += " " + log.source + " rows " + std::to_string(cut + 1) + "-" +
                                std::to_string(log.NumRows()) + " (" +
                                Percent(1.0 - static_cast<double>(cut) / log.NumRows()) + ")";
    }
  } else {
    for (const Log& log : logs) estimation.push_back(MakeBalanceData(log));
    validation_description = "none (--holdout_fraction=0 and no --validate)";
  }
  context.validation_description = validation_description;
  context.notes.push_back("Validation data: " + validation_description + ".");
  if (!vehicle.config.effects.empty()) {
    context.notes.push_back(
        "The config enables effects; linear_kf uses the paper's linear "
        "balance model without them.");
  }

  LinearBaselineOptions options;
  options.process_noise = FLAGS_process_noise;
  std::fprintf(stderr,
               "identify: linear_kf on %zu estimation part(s): excitation, thrust map, "
               "sigma map, R, Kalman filter, reconstruction ...\n",
               estimation.size());
  const auto t0 = std::chrono::steady_clock::now();
  const LinearBaselineResult result =
      RunLinearBaseline(vehicle.parameters, estimation, validation, options);
  std::fprintf(stderr, "identify: estimated in %.3f s (%d Kalman updates)\n", SecondsSince(t0),
               result.kf.updates);

  // Everything is known: only now write.
  const std::string dir = run.out;
  MakeOutputFolder(dir + "/plots");
  std::set<std::string> taken;
  std::vector<std::string> stems, validation_stems;
  for (const BalanceData& d : estimation) stems.push_back(d.name);
  for (const BalanceData& d : validation) validation_stems.push_back(d.name);
  const std::vector<std::string> names = UniqueNames(stems, &taken);
  std::vector<std::string> validation_names;
  if (validate_paths.empty()) {
    validation_names = names;  // the held-out part of the same log
  } else {
    validation_names = UniqueNames(validation_stems, &taken);
  }

  nlohmann::json files = nlohmann::json::array();
  auto write = [&](const std::string& name, const std::string& text) {
    WriteFileAtomically(dir + "/" + name, text);
    files.push_back(name);
  };
  write("config.yaml", vehicle.ResolvedConfig());
  write("thrust_map.csv", ThrustMapCsv(result));
  write("sigma_map.csv", SigmaMapCsv(result));
  write("kf_history.csv", KfHistoryCsv(result));
  // One reconstruction file per log: its estimation part and its held-out part.
  std::map<std::string, std::pair<std::vector<const Reconstruction*>, std::vector<std::string>>>
      per_log;
  for (size_t i = 0; i < result.estimation.size(); ++i) {
    per_log[names[i]].first.push_back(&result.estimation[i]);
    per_log[names[i]].second.push_back("estimation");
  }
  for (size_t i = 0; i < result.validation.size(); ++i) {
    per_log[validation_names[i]].first.push_back(&result.validation[i]);
    per_log[validation_names[i]].second.push_back("validation");
  }
  for (const auto& [name, parts] : per_log) {
    write("reconstruction_" + name + ".csv", ReconstructionCsv(parts.first, parts.second));
  }

  std::fprintf(stderr, "identify: plotting (gnuplot) ...\n");
  nlohmann::json plots = nlohmann::json::array();
  std::string plot_error;
  for (const std::string& file :
       RenderFigures(BaselineFigures(result, names, validation_names), dir + "/plots",
                     &plot_error)) {
    plots.push_back("plots/" + file);
  }
  context.outputs = {{"files", files}, {"plots", plots}};
  if (!plot_error.empty()) {
    context.outputs["plots_skipped"] = plot_error;
    context.notes.push_back("plots skipped: " + plot_error);
  }
  nlohmann::json report = LinearBaselineReportJson(result, vehicle.parameters, context);
  const PlausibilityVerdict plausibility = AddPlausibility(vehicle.parameters, {}, &report);
  WriteJson(dir + "/report.json", report);
  if (run.print_estimates) PrintEstimates(result);
  PrintPlausibility(plausibility);
  std::fprintf(stderr, "identify: done in %.2f s -> %s/report.json%s\n", SecondsSince(start),
               dir.c_str(), plot_error.empty() ? "" : " (plots skipped)");
  return report;
}

std::string LinearKfCheckText(const std::vector<Log>& logs, const std::string& config_path) {
  std::string out;
  ParameterSet config;
  std::string config_note;
  try {
    const std::string path =
        config_path.empty() ? FLAGS_data_dir + "/configs/glmav.yaml" : config_path;
    config = LoadVehicleConfig(path).parameters;
    config_note = "d and scales from " + path + ", sigma = 1";
  } catch (const InputError&) {
    if (!config_path.empty()) throw;
  }
  std::vector<BalanceData> all;
  for (const Log& log : logs) {
    if (log.kind != LogKind::kBalance) {
      out += "linear_kf check: " + log.source +
             " is a flight log; the linear_kf excitation check applies to balance logs only\n";
      continue;
    }
    all.push_back(MakeBalanceData(log));
  }
  auto check = [&](const std::vector<BalanceData>& data) {
    std::vector<const BalanceData*> pointers;
    for (const BalanceData& d : data) pointers.push_back(&d);
    const ExcitationReport report =
        config.size() > 0 ? CheckBalanceExcitation(config, data) : CheckLemma1(pointers);
    std::string title;
    for (const BalanceData& d : data) title += (title.empty() ? "" : ", ") + d.source;
    return "\n" + title + ": " + ExcitationText(report, pointers) +
           (config_note.empty() ? "" : "  (eigenvalues: " + config_note + ")\n");
  };
  for (const BalanceData& d : all) out += check({d});
  if (all.size() > 1) out += check(all);
  return out;
}

}  // namespace coaxid
