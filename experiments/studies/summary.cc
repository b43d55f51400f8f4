#include "experiments/studies/summary.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

#include "core/statistics.h"
#include "experiments/simulation/simulate_experiment.h"
#include "experiments/studies/confusion.h"
#include "experiments/studies/share_threshold.h"
#include "experiments/studies/points.h"

namespace coaxid {
namespace {

nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

double BinomialLogPmf(int n, int k, double p) {
  return std::lgamma(n + 1.0) - std::lgamma(k + 1.0) - std::lgamma(n - k + 1.0) + k * std::log(p) +
         (n - k) * std::log1p(-p);
}

// Effects of the point's truth that the config does not declare.
std::vector<std::string> UndeclaredEffects(const StudySpec& spec, int point) {
  if (spec.randomise.enabled) return {};  // each run has its own truth: see the confusion table
  const std::vector<Scenario> scenarios = PointScenarios(spec, point, spec.base_seed);
  std::set<std::string> declared;
  for (const auto& e : spec.config.effects) declared.insert(e.first);
  std::vector<std::string> out;
  for (const std::string& e : MakeTruthVehicle(spec.config, scenarios.front()).EffectNames()) {
    if (!declared.count(e)) out.push_back(e);
  }
  return out;
}

// truth: per run (a randomised study draws one per run).
nlohmann::json ParameterStatistics(const std::vector<double>& estimate,
                                   const std::vector<double>& std,
                                   const std::vector<double>& truth) {
  std::vector<double> error, relative_error, with_std;
  int covered = 0, n_std = 0;
  for (size_t i = 0; i < estimate.size(); ++i) {
    error.push_back(estimate[i] - truth[i]);
    relative_error.push_back(truth[i] != 0 ? error.back() / std::fabs(truth[i]) : NAN);
    if (std::isfinite(std[i])) {
      ++n_std;
      with_std.push_back(std[i]);
      if (std::fabs(estimate[i] - truth[i]) <= kIntervalHalfWidthInStd * std[i]) ++covered;
    }
  }
  const double spread = StdDev(estimate), mean_std = Mean(with_std);
  const auto [lo, hi] = BinomialBand(n_std, kNominalCoverage);
  nlohmann::json coverage = {{"covered", covered}, {"runs_with_std", n_std}};
  if (n_std > 0) {
    coverage["rate"] = static_cast<double>(covered) / n_std;
    coverage["band"] = {static_cast<double>(lo) / n_std, static_cast<double>(hi) / n_std};
    coverage["in_band"] = covered >= lo && covered <= hi;
  }
  return {{"runs", estimate.size()},
          {"truth", Number(Mean(truth))},
          {"mean", Number(Mean(estimate))},
          {"bias", Number(Mean(error))},
          {"relative_bias", Number(Mean(relative_error))},
          {"spread", Number(spread)},
          {"rmse", Number(Rms(error))},
          {"mean_std", Number(mean_std)},
          {"spread_over_std", Number(spread / mean_std)},
          {"coverage", coverage}};
}

nlohmann::json MethodSummary(const std::string& method,
                             const std::vector<const nlohmann::json*>& runs,
                             const std::vector<std::string>& undeclared) {
  int ok = 0, failed = 0;
  std::string first_error;
  // Parameters in first-seen order (the method's order).
  std::vector<std::string> names;
  std::map<std::string, std::vector<double>> estimates, stds, truths;
  std::map<std::string, int> detected;
  int false_alarms = 0;
  for (const nlohmann::json* r : runs) {
    if (!(*r)["methods"].contains(method)) continue;
    const nlohmann::json& m = (*r)["methods"][method];
    if (!m["ok"].get<bool>()) {
      ++failed;
      if (first_error.empty()) first_error = m["error"].get<std::string>();
      continue;
    }
    ++ok;
    for (const auto& [name, p] : m["parameters"].items()) {
      if (p["truth"].is_null() || p["estimate"].is_null()) continue;
      if (!estimates.count(name)) names.push_back(name);
      estimates[name].push_back(p["estimate"].get<double>());
      stds[name].push_back(p["std"].is_null() ? NAN : p["std"].get<double>());
      truths[name].push_back(p["truth"].get<double>());
    }
    if (m.contains("added")) {
      // A randomised run's truth is its own draw, not the spec's.
      const std::set<std::string> truth = r->contains("draw")
                                              ? TruthEffectsOfDraw((*r)["draw"])
                                              : std::set<std::string>(undeclared.begin(),
                                                                      undeclared.end());
      bool false_alarm = false;
      for (const auto& a : m["added"]) {
        const std::string e = a.get<std::string>();
        if (truth.count(e)) {
          ++detected[e];
        } else {
          false_alarm = true;
        }
      }
      false_alarms += false_alarm;
    }
  }
  nlohmann::json out = {{"runs_ok", ok}, {"runs_failed", failed}};
  if (!first_error.empty()) out["first_error"] = first_error;
  nlohmann::json parameters = nlohmann::json::object();
  for (const std::string& name : names) {
    parameters[name] = ParameterStatistics(estimates[name], stds[name], truths[name]);
  }
  out["parameters"] = parameters;
  if (method == "discover") {
    nlohmann::json detection = nlohmann::json::object();
    for (const std::string& e : undeclared) detection[e] = RateJson(detected[e], ok);
    out["detection"] = detection;
    out["false_alarm"] = RateJson(false_alarms, ok);
  }
  return out;
}

std::string Format(const nlohmann::json& v, const char* format = "%.4g") {
  if (!v.is_number()) return "-";
  char text[48];
  std::snprintf(text, sizeof text, format, v.get<double>());
  return text;
}

}  // namespace

nlohmann::json RateJson(int count, int n) {
  if (n == 0) {
    return {{"count", 0}, {"runs", 0}, {"rate", nullptr}, {"interval", {nullptr, nullptr}}};
  }
  const double z = kIntervalHalfWidthInStd, p = static_cast<double>(count) / n;
  const double centre = (p + z * z / (2 * n)) / (1 + z * z / n);
  const double half = z / (1 + z * z / n) * std::sqrt(p * (1 - p) / n + z * z / (4.0 * n * n));
  return {{"count", count},
          {"runs", n},
          {"rate", p},
          {"interval", {std::max(0.0, centre - half), std::min(1.0, centre + half)}}};
}

std::pair<int, int> BinomialBand(int n, double p, double confidence) {
  if (n <= 0) return {0, 0};
  const double tail = (1 - confidence) / 2;
  std::vector<double> pmf(n + 1);
  for (int k = 0; k <= n; ++k) pmf[k] = std::exp(BinomialLogPmf(n, k, p));
  int lo = 0;
  double below = 0;  // P(X < lo)
  while (lo < n && below + pmf[lo] <= tail) below += pmf[lo++];
  int hi = n;
  double above = 0;  // P(X > hi)
  while (hi > 0 && above + pmf[hi] <= tail) above += pmf[hi--];
  return {lo, hi};
}

nlohmann::json SummarizeStudy(const StudySpec& spec, const std::vector<nlohmann::json>& records) {
  std::vector<std::vector<const nlohmann::json*>> by_point(spec.sweep.NumPoints());
  for (const nlohmann::json& r : records) by_point[r["point"].get<int>()].push_back(&r);
  nlohmann::json points = nlohmann::json::array();
  for (int p = 0; p < spec.sweep.NumPoints(); ++p) {
    int simulation_failures = 0;
    for (const nlohmann::json* r : by_point[p]) simulation_failures += (*r)["simulation"] != "ok";
    const std::vector<std::string> undeclared = UndeclaredEffects(spec, p);
    nlohmann::json methods = nlohmann::json::object();
    for (StudyMethod m : spec.methods) {
      methods[StudyMethodName(m)] = MethodSummary(StudyMethodName(m), by_point[p], undeclared);
    }
    points.push_back({{"point", p},
                      {"label", spec.sweep.Label(p)},
                      {"value", Number(spec.sweep.Value(p))},
                      {"runs", by_point[p].size()},
                      {"simulation_failures", simulation_failures},
                      {"undeclared_effects", undeclared},
                      {"methods", methods}});
  }
  nlohmann::json methods = nlohmann::json::array();
  for (StudyMethod m : spec.methods) methods.push_back(StudyMethodName(m));
  nlohmann::json summary = {
      {"study", spec.name},
      {"spec", std::filesystem::absolute(spec.source).lexically_normal().string()},
      {"spec_hash", spec.hash},
      {"setting", SweepSettingName(spec.sweep.setting)},
      {"methods", methods},
      {"seeds", spec.seed_count},
      {"base_seed", spec.base_seed},
      {"runs_total", spec.NumRuns()},
      {"runs_done", records.size()},
      {"nominal_coverage", kNominalCoverage},
      {"points", points}};
  if (!spec.sweep.parameter.empty()) summary["parameter"] = spec.sweep.parameter;
  const bool discover = std::find(spec.methods.begin(), spec.methods.end(),
                                  StudyMethod::kDiscover) != spec.methods.end();
  if (spec.randomise.enabled && discover) {
    summary["confusion"] = ConfusionSummary(records);
    summary["share_threshold"] = ShareThresholdSummary(records);
  }
  return summary;
}

std::string StudySummaryMarkdown(const nlohmann::json& s) {
  std::string md = "# Study " + s["study"].get<std::string>() + "\n\nSpec `" +
                   s["spec"].get<std::string>() + "` (hash " + s["spec_hash"].get<std::string>() +
                   "), sweep: " + s["setting"].get<std::string>();
  if (s.contains("parameter")) md += " of " + s["parameter"].get<std::string>();
  md += "; " + std::to_string(s["runs_done"].get<int>()) + " of " +
        std::to_string(s["runs_total"].get<int>()) + " runs done (" +
        std::to_string(s["seeds"].get<int>()) + " seeds per point from " +
        std::to_string(s["base_seed"].get<uint64_t>()) + ").\n\n" +
        "Bias = mean(estimate - truth); spread = sample std of the estimates; mean std = the "
        "mean of the std each run reported; coverage = share of the runs whose estimate +- 1.96 "
        "std holds the truth, against the binomial 95 % band of that share for the nominal "
        "95 % (**outside** the band: the reported std are not honest at this point).\n";
  for (const auto& point : s["points"]) {
    md += "\n## Point " + point["label"].get<std::string>() + " (" +
          std::to_string(point["runs"].get<int>()) + " runs";
    if (point["simulation_failures"].get<int>() > 0) {
      md += ", " + std::to_string(point["simulation_failures"].get<int>()) + " simulations failed";
    }
    md += ")\n";
    for (const auto& [method, m] : point["methods"].items()) {
      md += "\n### " + method + ": " + std::to_string(m["runs_ok"].get<int>()) + " ok, " +
            std::to_string(m["runs_failed"].get<int>()) + " failed";
      if (m.contains("first_error")) md += " (first: " + m["first_error"].get<std::string>() + ")";
      md +=
          "\n\n| parameter | truth | bias | bias / truth | spread | mean std | spread / std "
          "| coverage | 95 % band |\n|---|---|---|---|---|---|---|---|---|\n";
      for (const auto& [name, p] : m["parameters"].items()) {
        const nlohmann::json& c = p["coverage"];
        std::string coverage = "-", band = "-";
        if (c.contains("rate")) {
          coverage = std::to_string(c["covered"].get<int>()) + "/" +
                     std::to_string(c["runs_with_std"].get<int>()) + " = " +
                     Format(c["rate"], "%.3f") + (c["in_band"].get<bool>() ? "" : " **outside**");
          band = Format(c["band"][0], "%.3f") + " - " + Format(c["band"][1], "%.3f");
        }
        md += "| " + name + " | " + Format(p["truth"]) + " | " + Format(p["bias"], "%.3g") + " | " +
              Format(p["relative_bias"], "%.2g") + " | " + Format(p["spread"], "%.3g") + " | " +
              Format(p["mean_std"], "%.3g") + " | " + Format(p["spread_over_std"], "%.2f") + " | " +
              coverage + " | " + band + " |\n";
      }
      if (m.contains("false_alarm")) {
        md += "\n";
        for (const auto& [effect, d] : m["detection"].items()) {
          md += "- detection of " + effect +
                " (in the truth, not declared): " + Format(d["rate"], "%.3f") + " (95 % interval " +
                Format(d["interval"][0], "%.2f") + " - " + Format(d["interval"][1], "%.2f") + ")\n";
        }
        const nlohmann::json& f = m["false_alarm"];
        md += "- false alarms (an effect added that the truth does not have): " +
              Format(f["rate"], "%.3f") + " (" + std::to_string(f["count"].get<int>()) + " of " +
              std::to_string(f["runs"].get<int>()) + " runs)\n";
      }
    }
  }
  if (s.contains("confusion")) md += ConfusionMarkdown(s["confusion"]);
  if (s.contains("share_threshold")) md += ShareThresholdMarkdown(s["share_threshold"]);
  return md;
}

}  // namespace coaxid
