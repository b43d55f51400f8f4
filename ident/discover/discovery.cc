#include "ident/discover/discovery.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "core/errors.h"
#include "core/report.h"
#include "core/report_values.h"
#include "core/stopwatch.h"

namespace coaxid {
namespace {

using Clock = std::chrono::steady_clock;

void Say(const DiscoveryOptions& o, const std::string& line) {
  if (o.progress) o.progress(line);
}

ModelSnapshot Snapshot(const Vehicle& vehicle, const OutputErrorResult& r,
                       const std::vector<EstimationLog>& estimation,
                       const std::vector<EstimationLog>& validation, const DiscoveryOptions& o) {
  ModelSnapshot s;
  s.vehicle = vehicle;
  s.vehicle.parameters = r.parameters;
  s.result = r;
  s.fit = ChannelFitErrors(estimation, r.predictions);
  s.residual_tests = AnalyseResiduals(estimation, r.predictions, o.residuals);
  if (!validation.empty()) {
    s.validation_predictions =
        PredictWithFixedParameters(s.vehicle, validation, r.noise, o.window_s, o.fit);
    s.validation = ChannelFitErrors(validation, s.validation_predictions);
    s.validation_residual_tests =
        AnalyseResiduals(validation, s.validation_predictions, o.residuals);
  }
  return s;
}

OutputErrorResult FitOrThrow(const Vehicle& v, const std::vector<EstimationLog>& logs,
                             const OutputErrorOptions& o, const std::string& what) {
  OutputErrorResult r = FitOutputError(v, logs, o);
  if (!r.usable) throw ComputationError(what + " failed: " + r.why_not_usable);
  return r;
}

nlohmann::json TestsJson(const std::vector<ChannelResidualTest>& tests) {
  nlohmann::json j = nlohmann::json::object();
  for (const ChannelResidualTest& t : tests) j[t.channel] = t.ToJson();
  return j;
}

nlohmann::json SnapshotJson(const ModelSnapshot& s, bool has_validation) {
  nlohmann::json j = {
      {"effects", s.vehicle.EffectNames()},
      {"parameters", ParametersJson(s.result)},
      {"scale", s.result.gauge.ToJson()},
      {"ratios", RatiosJson(s.result.ratios)},
      {"fit", FitJson(s.fit)},
      {"residual_tests", TestsJson(s.residual_tests)}};
  nlohmann::json noise = nlohmann::json::object();
  for (const auto& [name, v] : s.result.noise.std) noise[name] = v;
  j["noise_std"] = noise;
  if (has_validation) {
    j["validation"] = FitJson(s.validation);
    j["validation_residual_tests"] = TestsJson(s.validation_residual_tests);
  } else {
    j["validation"] = {{"overall_nrmse", nullptr}};
  }
  return j;
}

}  // namespace

bool DiscoveryOptions::IsValid(std::string* why) const {
  if (!(alpha > 0 && alpha < 1)) {
    *why = "alpha must be in (0, 1)";
    return false;
  }
  if (max_added < 0) {
    *why = "max_added must be >= 0";
    return false;
  }
  if (!(window_s > 0)) {
    *why = "window_s must be > 0";
    return false;
  }
  if (!dictionary.IsValid(why)) return false;
  if (!(fit_function_tolerance > 0 && fit_function_tolerance < 1)) {
    *why = "fit_function_tolerance must be in (0, 1)";
    return false;
  }
  if (residuals.lags < 1) {
    *why = "residual lags must be >= 1";
    return false;
  }
  return fit.IsValid(why);
}

DiscoveryResult Discover(const Vehicle& declared, const std::vector<EstimationLog>& estimation,
                         const std::vector<EstimationLog>& validation,
                         const DiscoveryOptions& options) {
  const auto start = Clock::now();
  std::string why;
  if (!options.IsValid(&why)) throw InputError("discover options: " + why);
  if (estimation.empty()) throw InputError("discover: no estimation log");
  DiscoveryResult out;
  DiscoveryOptions o = options;
  o.fit.function_tolerance = std::max(o.fit.function_tolerance, o.fit_function_tolerance);

  Say(options, "discover: fitting the declared model (" +
                   std::to_string(declared.parameters.FreeIndices().size()) + " free parameters)");
  OutputErrorResult fit = FitOrThrow(declared, estimation, o.fit, "the declared model's fit");
  Vehicle current = declared;
  current.parameters = fit.parameters;
  out.baseline = Snapshot(current, fit, estimation, validation, options);

  CandidatePass pass = LinearisePass(current, fit, estimation, o.fit);
  Say(options, "discover: sensitivities of " + std::to_string(pass.candidates.size()) +
                   " candidate effects along the fit: " + NumberText(pass.seconds, "%.1f s"));
  for (int round = 1; round <= options.max_added + 1; ++round) {
    Say(options, "discover: round " + std::to_string(round) + ": scoring candidates against " +
                     (out.added.empty() ? std::string("the declared model")
                                        : "the model with " + std::to_string(out.added.size()) +
                                              " added effect(s)"));
    std::vector<CandidateScore> scores =
        ScoreCandidates(pass, estimation, options.alpha, round);
    for (const CandidateScore& s : scores) {
      char line[256];
      std::snprintf(line, sizeof(line),
                    "  %-18s F = %-10.4g p = %-10.3g p_holm = %-10.3g (white-noise p = %.3g) %s",
                    s.effect.c_str(), s.statistic, s.p_value, s.p_corrected, s.white_p_value,
                    !s.testable ? "not testable" : s.passes ? "passes" : "fails");
      Say(options, line);
    }
    bool accepted = false;
    if (static_cast<int>(out.added.size()) < options.max_added) {
      for (CandidateScore& s : scores) {
        if (!s.passes) break;  // passing candidates come first, best first
        Say(options, "discover: confirming " + s.effect + " by a joint refit (" +
                         NumberText(SecondsSince(start), "%.1f s") + " so far)");
        CandidatePass next;
        if (ConfirmCandidate(pass, estimation, o.fit, options.alpha, &s, &next)) {
          Say(options, "discover: added " + s.effect + " (Wald p = " +
                           NumberText(s.wald_p_value, "%.3g") + ")");
          pass = std::move(next);
          out.added.push_back(s.effect);
          accepted = true;
          break;
        }
        Say(options, "discover: " + s.effect + " not confirmed: " + s.why_not_confirmed);
      }
    }
    out.candidates.insert(out.candidates.end(), scores.begin(), scores.end());
    if (!accepted) break;
  }
  current = pass.fitted;
  fit = pass.fit;
  out.final = out.added.empty() ? out.baseline
                                : Snapshot(current, fit, estimation, validation, options);

  for (const ChannelResidualTest& t : out.final.residual_tests) {
    // Structured: autocorrelated (Ljung-Box, which removes the mean), or
    // offset by more than its noise; and well above its noise either way.
    const bool structured = t.ljung_box_p < options.alpha || std::fabs(t.mean) > t.noise_std;
    if (!(structured && t.rms > options.unexplained_rms_ratio * t.noise_std)) continue;
    UnexplainedChannel u;
    u.channel = t.channel;
    u.ljung_box_p = t.ljung_box_p;
    u.rms = t.rms;
    u.noise_std = t.noise_std;
    if (!t.correlations.empty()) {
      u.correlates_with = t.correlations.front().with;
      u.correlation = t.correlations.front().r;
    }
    char text[512];
    std::snprintf(text, sizeof(text),
                  "residual still structured (Ljung-Box p = %.2g, mean %.3g, rms %.3g = %.1f x "
                  "its sample-to-sample noise %.3g); strongest correlation: %s (r = %.2f); no "
                  "effect in the library passes for it",
                  t.ljung_box_p, t.mean, t.rms, t.noise_std > 0 ? t.rms / t.noise_std : INFINITY,
                  t.noise_std, u.correlates_with.c_str(), u.correlation);
    u.why = text;
    u.generic = SearchChannelDictionary(estimation, out.final.result.predictions, t.channel,
                                        options.dictionary);
    out.unexplained.push_back(u);
  }
  out.seconds = SecondsSince(start);
  return out;
}

nlohmann::json DiscoveryJson(const DiscoveryResult& r, const DiscoveryOptions& options) {
  const bool has_validation = !r.baseline.validation.empty();
  nlohmann::json candidates = nlohmann::json::array();
  for (const CandidateScore& s : r.candidates) candidates.push_back(s.ToJson());
  nlohmann::json unexplained = nlohmann::json::array();
  for (const UnexplainedChannel& u : r.unexplained) {
    unexplained.push_back({{"channel", u.channel},
                           {"ljung_box_p", u.ljung_box_p},
                           {"rms", u.rms},
                           {"noise_std", u.noise_std},
                           {"correlates_with", u.correlates_with},
                           {"correlation", u.correlation},
                           {"why", u.why},
                           {"generic_candidate", u.generic.ToJson()}});
  }
  nlohmann::json added_parameters = nlohmann::json::object();
  const nlohmann::json final_parameters =
      ParametersJson(r.final.result);
  for (const std::string& e : r.added) {
    for (auto it = final_parameters.begin(); it != final_parameters.end(); ++it) {
      if (it.key().rfind(e + ".", 0) == 0) added_parameters[it.key()] = it.value();
    }
  }
  return {{"baseline", SnapshotJson(r.baseline, has_validation)},
          {"candidates", candidates},
          {"added", r.added},
          {"added_parameters", added_parameters},
          {"final", SnapshotJson(r.final, has_validation)},
          {"unexplained", unexplained},
          {"settings",
           {{"alpha", options.alpha},
            {"correction", "Holm over the candidates tested in each round"},
            {"candidate_test",
             "score test of the nested model linearised at the current fit (candidate output "
             "sensitivities, estimated directions projected out), cluster-robust over "
             "multiple-shooting segments and balance holds (Hotelling T^2, F(q, M - q)); the "
             "best passing candidate is refitted jointly and confirmed by the cluster-robust "
             "Wald test of its parameters"},
            {"whiteness_test", "Ljung-Box, chi-square p-value by the regularized incomplete gamma"},
            {"ljung_box_lags", options.residuals.lags},
            {"unexplained_rms_ratio", options.unexplained_rms_ratio},
            {"prediction_window_s", options.window_s}}},
          {"seconds", r.seconds}};
}

}  // namespace coaxid
