#include "experiments/cli/discover.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/plot.h"
#include "core/report.h"
#include "core/report_values.h"
#include "dynamics/effects/effect_library.h"
#include "experiments/cli/cli.h"
#include "experiments/cli/estimation_io.h"
#include "experiments/cli/flag_checks.h"
#include "experiments/cli/flags.h"
#include "experiments/cli/plausibility_report.h"
#include "ident/noise_weights.h"
#include "ident/baseline/balance_holds.h"
#include "ident/discover/discovery.h"
#include "ident/discover/practical_significance.h"

DEFINE_double(alpha, 0.01,
              "discover: significance level of the candidate tests (family-wise per round, Holm)");
DEFINE_int32(max_added, 4, "discover: add at most this many effects");
DEFINE_double(min_share_of_excess, 0.3,
              "discover: the least share of its channels' excess error (rms^2 - noise^2) an "
              "effect must remove, on the estimation and the held-out data, to be added");
DEFINE_double(min_share_to_pair, coaxid::DiscoveryOptions().min_share_to_pair,
              "discover: a round that adds nothing is refitted beside a significant refit at "
              "its own bound that removes at least this share of its channels' excess error "
              "(never above --min_share_of_excess)");
DEFINE_double(fit_rate_hz, coaxid::DiscoveryOptions().fit_rate_hz,
              "discover: fit flight logs sampled faster than this [Hz] with runs of their rows "
              "averaged (pairs at 200 Hz; each fit costs half); 0: every log at its own rate");
DEFINE_double(search_window_s, coaxid::DiscoveryOptions().search_window_s,
              "discover: search flight logs longer than twice this [s] on their first "
              "search_window_s, then confirm what that adds on the whole logs and search them "
              "once more; 0: search the whole logs");
DECLARE_double(segment_s);

namespace coaxid {
namespace {

namespace fs = std::filesystem;

constexpr const char* kDiscoverUsage =
    "usage: coaxid discover --logs=A.csv[,B.csv] --config=F --out=DIR [--validate=C.csv] "
    "[--holdout_fraction=0.2] [--alpha=0.01] [--max_added=4] [--segment_s=1] [--fit_rate_hz=100] "
    "[--search_window_s=20]";

std::string Num(double v, const char* fmt = "%.4g") {
  if (!std::isfinite(v)) return "-";
  char b[64];
  std::snprintf(b, sizeof(b), fmt, v);
  return b;
}

Figure Autocorrelations(const DiscoveryResult& r) {
  Figure f;
  f.title = "Residual autocorrelation, before (declared model) and after";
  f.columns = 3;
  for (size_t c = 0; c < r.baseline.residual_tests.size(); ++c) {
    const ChannelResidualTest& b = r.baseline.residual_tests[c];
    PlotPanel p;
    p.title = b.channel + " (Ljung-Box p " + Num(b.ljung_box_p, "%.2g");
    p.x_label = "lag [samples]";
    PlotSeries before{"before", {}, {}, "linespoints pt 7 ps 0.4 lc rgb '#999999'"};
    for (size_t k = 0; k < b.autocorrelation.size(); ++k) {
      before.x.push_back(k);
      before.y.push_back(b.autocorrelation[k]);
    }
    p.series.push_back(before);
    for (const ChannelResidualTest& a : r.final.residual_tests) {
      if (a.channel != b.channel) continue;
      p.title += " -> " + Num(a.ljung_box_p, "%.2g");
      PlotSeries after{"after", {}, {}, "linespoints pt 7 ps 0.4 lc rgb 'red'"};
      for (size_t k = 0; k < a.autocorrelation.size(); ++k) {
        after.x.push_back(k);
        after.y.push_back(a.autocorrelation[k]);
      }
      p.series.push_back(after);
    }
    p.title += ")";
    f.panels.push_back(p);
  }
  return f;
}

Figure Spectra(const DiscoveryResult& r) {
  Figure f;
  f.title = "Residual periodogram, before and after";
  f.columns = 3;
  for (const ChannelResidualTest& b : r.baseline.residual_tests) {
    PlotPanel p;
    p.title = b.channel;
    p.x_label = "frequency [Hz]";
    p.log_y = true;
    PlotSeries before{"before", b.frequency_hz, b.power, "lines lc rgb '#999999'"};
    p.series.push_back(before);
    for (const ChannelResidualTest& a : r.final.residual_tests) {
      if (a.channel == b.channel) p.series.push_back({"after", a.frequency_hz, a.power, "lines lc rgb 'red'"});
    }
    for (PlotSeries& s : p.series) {
      for (double& v : s.y) v = std::max(v, 1e-300);
    }
    f.panels.push_back(p);
  }
  return f;
}

// "; blind at the bounds (refitted with Cx, Cy at their config values)".
std::string RestartsText(const CandidateScore& s) {
  if (s.restart_values.empty()) return "";
  std::string names;
  for (const auto& [name, value] : s.restart_values) names += (names.empty() ? "" : ", ") + name;
  return std::string(s.blind_at_bounds ? "; blind at the bounds" : "") + " (refitted with " +
         names + " at their config values)";
}

std::string FitTable(const DiscoveryResult& r, bool has_validation) {
  std::ostringstream o;
  o << "| channel | rms before | rms after | nrmse before | nrmse after |";
  if (has_validation) o << " held-out nrmse before | held-out nrmse after |";
  o << "\n|---|---|---|---|---|" << (has_validation ? "---|---|" : "") << "\n";
  for (const auto& [name, b] : r.baseline.fit) {
    const FitError& a = r.final.fit.at(name);
    o << "| " << name << " | " << Num(b.rms) << " | " << Num(a.rms) << " | " << Num(b.nrmse)
      << " | " << Num(a.nrmse) << " |";
    if (has_validation) {
      auto bv = r.baseline.validation.find(name);
      auto av = r.final.validation.find(name);
      o << " " << (bv == r.baseline.validation.end() ? "-" : Num(bv->second.nrmse)) << " | "
        << (av == r.final.validation.end() ? "-" : Num(av->second.nrmse)) << " |";
    }
    o << "\n";
  }
  return o.str();
}

std::string ReportMarkdown(const DiscoveryResult& r, const std::vector<std::string>& logs,
                           const std::string& validation, const std::vector<std::string>& plots,
                           const std::string& plot_error, const DiscoveryOptions& options,
                           const PlausibilityVerdict& plausibility) {
  const bool has_validation = !r.baseline.validation.empty();
  std::ostringstream o;
  o << "# coaxid discover: what the declared model lacks\n\n";
  o << "Logs: ";
  for (const std::string& l : logs) o << "`" << l << "` ";
  o << "\n\nHeld-out data: " << validation << "\n\n";
  o << "Rates fitted (flight logs sampled faster than " << Num(options.fit_rate_hz)
    << " Hz are fitted with runs of their rows averaged; errors and residuals below are on "
       "those rows):\n\n";
  for (const std::vector<LogAtFitRate>* set : {&r.estimation, &r.validation}) {
    for (const LogAtFitRate& a : *set) o << "- " << a.note << "\n";
  }
  o << "\n";
  const DiscoveryResult::SearchWindow& w = r.search_window;
  if (!w.logs.empty()) {
    o << "Search window: the first " << Num(w.seconds) << " s of ";
    for (const std::string& l : w.logs) o << "`" << l << "` ";
    if (w.used) {
      o << "were searched (round" << (w.rounds > 1 ? "s 1-" : " ") << w.rounds << ", which added "
        << (w.added.empty() ? std::string("nothing") : Joined(w.added, ", "))
        << "); the declared model and the model they ended with were then fitted to the whole "
           "logs, what they added judged again there, and the later rounds ran on the whole "
           "logs.\n\n";
    } else {
      o << "were to be searched first, but " << w.note << ": the whole logs were searched.\n\n";
    }
  }
  o << "Declared effects: ";
  const auto declared = r.baseline.vehicle.EffectNames();
  o << (declared.empty() ? "none (the paper's model)" : "");
  for (const std::string& e : declared) o << e << " ";
  o << "\n\n## Verdict\n\n";
  if (r.added.empty()) {
    o << "No library effect passes the test: nothing was added.\n";
  } else {
    o << "Added, in order: ";
    for (const std::string& e : r.added) o << "**" << e << "** ";
    o << "\n";
  }
  for (const RemovedEffect& e : r.removed) {
    if (e.on_whole_logs) {
      o << "\nRemoved " << e.effect << " again: the search window added it, but on the whole "
        << "logs, the rest refitted warm without it, it removes only "
        << ShareText(e.share_of_excess, e.share_of_excess_held_out) << ".\n";
      continue;
    }
    if (e.made_redundant_by.empty()) {
      o << "\nRemoved " << e.effect << " again: without it, the rest refitted warm from its refit, "
        << "it removes only " << ShareText(e.share_of_excess, e.share_of_excess_held_out)
        << ": its refit's gain came from moving the declared parameters, not from it.\n";
      continue;
    }
    o << "\nRemoved " << e.effect << " (added earlier): in the model with " << e.made_redundant_by
      << " it removes only " << ShareText(e.share_of_excess, e.share_of_excess_held_out)
      << ": it was standing in for " << e.made_redundant_by << ".\n";
  }
  if (!r.symptoms.empty()) {
    o << "\nDeclared parameters the declared fit left at a bound or far outside their physical "
         "range (a symptom of a missing effect):\n\n";
    for (const ParameterSymptom& b : r.symptoms) o << "- " << b.text << "\n";
  }
  if (!r.unexplained.empty()) {
    o << "\nChannels whose residual is still structured and that no library effect explains:\n\n";
    for (const UnexplainedChannel& u : r.unexplained) o << "- **" << u.channel << "**: " << u.why << "\n";
  }
  o << "\n## Plausibility of the final model\n\n";
  if (plausibility.DescribesVehicle()) {
    o << "Plausible: " << plausibility.Summary().substr(std::string("plausible: ").size()) << ".\n";
  } else {
    o << "**The model does not describe this vehicle.**\n\n";
    for (const PlausibilityFinding& f : plausibility.findings) o << "- " << f.text << "\n";
  }
  o << "\n## Error per channel, before (declared model) and after\n\n" << FitTable(r, has_validation);
  o << "\n## Candidates\n\nScore test linearised at the current fit (cluster-robust, "
       "Holm-corrected p) to shortlist; the shortlisted ones refitted jointly and judged on the "
       "refit: cluster-robust Wald p, no parameter at a bound, and the share of its channels' "
       "excess error (rms^2 - noise^2) removed, at least "
    << Num(100 * options.min_share_of_excess, "%.0f")
    << " % on the estimation and the held-out data. A round that adds nothing but holds a "
       "significant refit with a parameter of its own at a bound is refitted with that effect in "
       "the model (rows \"beside\" it); the best candidate qualifying there is added with it "
       "when the pair qualifies.\n\n";
  o << "| round | effect | F | p | p (Holm) | predicted share | passes | refit: Wald p | share "
       "removed (held out) | decision | channels / reason |\n"
       "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const CandidateScore& s : r.candidates) {
    o << "| " << s.round << (s.beside.empty() ? "" : " (beside " + s.beside + ")") << " | "
      << s.effect << " | "
      << (s.testable ? Num(s.statistic) : "-") << " | " << (s.testable ? Num(s.p_value, "%.3g") : "-")
      << " | " << (s.testable ? Num(s.p_corrected, "%.3g") : "-") << " | "
      << (s.testable ? Num(s.predicted_share, "%.3g") : "-") << " | "
      << (!s.testable ? "not testable" : s.passes ? "yes" : "no") << RestartsText(s) << " | "
      << (s.refitted ? Num(s.wald_p_value, "%.3g") : "-") << " | "
      << (s.refitted ? Num(100 * s.share_of_excess, "%.1f") + " % (" +
                           (std::isfinite(s.share_of_excess_held_out)
                                ? Num(100 * s.share_of_excess_held_out, "%.1f") + " %"
                                : std::string("-")) +
                           ")"
                     : "-")
      << " | "
      << (s.confirmed ? (s.added_with.empty() ? "qualifies"
                                              : "added with " + s.added_with + " (paired refit)")
          : s.why_not_confirmed.empty() ? "-"
                                        : s.why_not_confirmed)
      << " | "
      << (s.testable ? s.reason : s.why_not_testable) << " |\n";
  }
  bool any_generic = false;
  for (const UnexplainedChannel& u : r.unexplained) any_generic = any_generic || !u.generic.terms.empty();
  if (any_generic) {
    o << "\n## Unnamed candidates for the engineer to interpret (generic dictionary, not added)\n\n"
         "Forward orthogonal least squares over products of the inputs and measured states up to "
         "degree 2, model size by the extended BIC with the residual's effective sample size. "
         "These terms describe the residual; they are not a physical effect and were not added "
         "to the model.\n\n";
    for (const UnexplainedChannel& u : r.unexplained) {
      if (u.generic.terms.empty()) continue;
      o << "**" << u.channel << "** (explains " << Num(100 * u.generic.explained, "%.0f")
        << " % of the residual energy; EBIC " << Num(u.generic.criterion_none) << " -> "
        << Num(u.generic.criterion) << "):\n\n| term | coefficient | ERR |\n|---|---|---|\n";
      for (const DictionaryTerm& t : u.generic.terms) {
        o << "| " << t.name << " | " << Num(t.coefficient, "%.4g") << " | " << Num(t.err, "%.3f")
          << " |\n";
      }
      o << "\n";
    }
  }
  if (!r.added.empty()) {
    o << "\n## Added effects' parameters (final joint fit, Cramér-Rao std)\n\n| parameter | value | std |\n|---|---|---|\n";
    const IdentifiabilityReport& id = r.final.result.identifiability;
    for (size_t k = 0; k < id.names.size(); ++k) {
      for (const std::string& e : r.added) {
        if (id.names[k].rfind(e + ".", 0) != 0) continue;
        o << "| " << id.names[k] << " | " << Num(r.final.result.parameters.Value(id.names[k]))
          << " | " << (id.identifiable[k] ? Num(id.std[k], "%.2g") : "not identifiable") << " |\n";
      }
    }
  }
  o << "\n## Residual tests (estimation data), before and after\n\n";
  o << "| channel | Ljung-Box p before | after | rms / noise before | after | strongest correlation after |\n|---|---|---|---|---|---|\n";
  for (const ChannelResidualTest& b : r.baseline.residual_tests) {
    for (const ChannelResidualTest& a : r.final.residual_tests) {
      if (a.channel != b.channel) continue;
      o << "| " << b.channel << " | " << Num(b.ljung_box_p, "%.2g") << " | "
        << Num(a.ljung_box_p, "%.2g") << " | "
        << Num(b.noise_std > 0 ? b.rms / b.noise_std : NAN, "%.2f") << " | "
        << Num(a.noise_std > 0 ? a.rms / a.noise_std : NAN, "%.2f") << " | "
        << (a.correlations.empty() ? "-" : a.correlations.front().with + " (r = " +
                                                Num(a.correlations.front().r, "%.2f") + ")")
        << " |\n";
    }
  }
  o << "\n## Plots\n\n";
  for (const std::string& p : plots) o << "![" << p << "](" << p << ")\n\n";
  if (!plot_error.empty()) o << "Plots skipped: " << plot_error << "\n";
  o << "\nMethod: the declared model is fitted by output error (all free parameters "
       "jointly). Every library effect it lacks is scored by the score test of the nested model "
       "linearised at the fit: the candidate's output sensitivities along the fitted trajectory "
       "(CVODES), with the directions already estimated (segment states, parameters) projected "
       "out. Its p-value is cluster-robust (Hotelling T^2 over clusters of flight rows three "
       "times the residual correlation time long and over balance holds, centred per log), so "
       "autocorrelated flight residuals do not make false "
       "alarms; the white-noise p is shown for comparison. p-values are Holm-corrected over the "
       "candidates tested in a round. The best passing candidate is refitted jointly and kept "
       "only if the cluster-robust Wald test of its parameters at the refit passes. Whiteness: "
       "Ljung-Box, p-value from the regularized incomplete gamma function. A channel is reported "
       "unexplained when it is structured (Ljung-Box p below alpha, or a mean offset beyond its "
       "noise) and its rms exceeds 1.5 times its sample-to-sample noise.\n";
  return o.str();
}

}  // namespace

int RunDiscover() {
  RequireFlag(FLAGS_logs, "logs", kDiscoverUsage);
  RequireFlag(FLAGS_config, "config", kDiscoverUsage);
  RequireFlag(FLAGS_out, "out", kDiscoverUsage);
  CheckOutputFolder(FLAGS_out);
  DiscoveryOptions options;
  options.alpha = FLAGS_alpha;
  options.max_added = FLAGS_max_added;
  options.min_share_of_excess = FLAGS_min_share_of_excess;
  options.window_s = FLAGS_segment_s;
  options.fit_rate_hz = FLAGS_fit_rate_hz;
  options.search_window_s = FLAGS_search_window_s;
  options.min_share_to_pair = FLAGS_min_share_to_pair;
  options.fit.segment_schedule_s = {std::min(0.25, FLAGS_segment_s), FLAGS_segment_s};
  if (FLAGS_segment_s <= 0.25) options.fit.segment_schedule_s = {FLAGS_segment_s};
  options.progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  options.fit.progress = options.progress;
  std::string why;
  if (!options.IsValid(&why)) throw InputError("discover: " + why);

  const Vehicle vehicle = LoadVehicle(FLAGS_config);
  std::vector<Log> logs, validate;
  for (const std::string& path : SplitList(FLAGS_logs)) logs.push_back(ReadLog(path));
  for (const std::string& path : SplitList(FLAGS_validate)) validate.push_back(ReadLog(path));
  if (logs.empty()) throw InputError("--logs names no file");
  const LogSplit split = SplitEstimationAndValidation(logs, validate, FLAGS_holdout_fraction);

  const DiscoveryResult r = Discover(vehicle, split.estimation, split.validation, options);

  const std::string dir = FLAGS_out;
  MakeOutputFolder(dir + "/plots");
  WriteFileAtomically(dir + "/config.yaml", r.final.vehicle.ResolvedConfig());
  FigureRenderer renderer;  // the figures are drawn side by side
  auto render = [&](const Figure& f, const std::string& name) {
    renderer.Add(f, dir + "/plots/" + name + ".png", "plots/" + name + ".png");
  };
  render(Autocorrelations(r), "residual_autocorrelation");
  render(Spectra(r), "residual_spectrum");
  for (size_t i = 0; i < r.estimation.size(); ++i) {  // the logs as fitted (fit_rate_hz)
    const EstimationLog& log = r.estimation[i].log;
    render(MeasuredVersusModelsFigure("estimation: " + log.source, log,
                                      {{"declared model", &r.baseline.result.predictions[i], "blue"},
                                       {"final model", &r.final.result.predictions[i], "red"}}),
           "fit_" + std::to_string(i + 1) + "_" + log.name);
  }
  for (size_t i = 0; i < r.validation.size(); ++i) {
    const EstimationLog& log = r.validation[i].log;
    render(MeasuredVersusModelsFigure("held out: " + log.source, log,
                                      {{"declared model", &r.baseline.validation_predictions[i], "blue"},
                                       {"final model", &r.final.validation_predictions[i], "red"}}),
           "validation_" + std::to_string(i + 1) + "_" + log.name);
  }
  std::string plot_error;
  const std::vector<std::string> plots = renderer.Finish(&plot_error);
  nlohmann::json j = DiscoveryJson(r, options);
  const std::map<std::string, double> sensor_noise = NoiseFromData(split.estimation).std;
  AddPlausibility(r.baseline.vehicle.parameters, sensor_noise, &j["baseline"]);
  const PlausibilityVerdict plausibility =
      AddPlausibility(r.final.vehicle.parameters, sensor_noise, &j["final"]);
  nlohmann::json logs_json = nlohmann::json::array();
  for (const Log& log : logs) logs_json.push_back(log.source);
  j["logs"] = logs_json;
  j["validation_data"] = split.description;
  j["outputs"] = {{"files", {"discovery.json", "report.md", "config.yaml"}}, {"plots", plots}};
  if (!plot_error.empty()) j["outputs"]["plots_skipped"] = plot_error;
  WriteJson(dir + "/discovery.json", j);
  std::vector<std::string> sources;
  for (const Log& log : logs) sources.push_back(log.source);
  WriteFileAtomically(dir + "/report.md",
                      ReportMarkdown(r, sources, split.description, plots, plot_error, options,
                                     plausibility));

  std::printf("discover: added %zu effect(s)", r.added.size());
  for (const std::string& e : r.added) std::printf(" %s", e.c_str());
  std::printf("\n");
  for (const UnexplainedChannel& u : r.unexplained) {
    std::printf("  unexplained %s: %s\n", u.channel.c_str(), u.why.c_str());
  }
  PrintPlausibility(plausibility);
  std::fprintf(stderr, "discover: done in %.1f s -> %s/discovery.json, report.md\n", r.seconds,
               dir.c_str());
  return 0;
}

}  // namespace coaxid
