#include "ident/candidate_scores.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "dynamics/effects/effect_library.h"
#include "dynamics/model_jacobian.h"
#include "dynamics/outputs.h"
#include "ident/residual_analysis.h"

namespace coaxid {
namespace {

// Channels of the logs whose output depends on the effect's parameters:
// |dy/dp| * scale above 1e-3 noise std at some sampled row.
std::vector<std::string> ReachedChannels(const Vehicle& v, const std::string& effect,
                                         const std::vector<EstimationLog>& logs,
                                         const NoiseWeights& noise) {
  std::vector<int> idx;
  std::vector<double> scales;
  for (const auto& spec : EffectLibrary()[EffectIndex(effect)].parameters) {
    const int i = v.parameters.IndexOrThrow(effect + "." + spec.name);
    idx.push_back(i);
    scales.push_back(v.parameters[i].scale);
  }
  const Eigen::VectorXd theta = v.parameters.Values();
  std::vector<std::string> reached;
  for (const EstimationLog& log : logs) {
    const int n = log.NumRows();
    const int step = std::max(1, n / 400);
    for (int k = 0; k < n; k += step) {
      Eigen::MatrixXd dydp;
      bool ok;
      if (log.kind == LogKind::kBalance) {
        double y[kNumBalanceChannels];
        ok = BalanceOutputJacobians(v.model, theta, log.inputs.input(k), idx, y, &dydp);
      } else {
        const Eigen::VectorXd x = InitialStateFromLog(log, k);
        double y[kNumFlightChannels];
        ok = FlightOutputJacobians(v.model, theta, x.data(), log.inputs.input(k), idx, y, nullptr,
                                   &dydp);
      }
      if (!ok) continue;
      for (int c = 0; c < log.NumChannels(); ++c) {
        const std::string& name = log.channel_names[c];
        if (std::find(reached.begin(), reached.end(), name) != reached.end()) continue;
        // Flight states respond through the dynamics, not directly: an effect
        // that moves a derivative reaches the states it drives. Approximated
        // by the derivative Jacobian below.
        double m = 0;
        for (size_t j = 0; j < idx.size(); ++j) {
          m = std::max(m, std::fabs(dydp(log.channels[c], j)) * scales[j]);
        }
        const auto it = noise.std.find(name);
        const double s = it == noise.std.end() ? 1 : it->second;
        if (m > 1e-3 * s) reached.push_back(name);
      }
      if (log.kind == LogKind::kFlight) {
        const Eigen::VectorXd x = InitialStateFromLog(log, k);
        Eigen::MatrixXd dfdx, dfdp;
        if (!DerivativeJacobians(v.model, theta, x.data(), log.inputs.input(k), idx, &dfdx, &dfdp)) {
          continue;
        }
        for (int c = 0; c < log.NumChannels(); ++c) {
          const int ch = log.channels[c];
          if (ch >= kNumStates) continue;
          const std::string& name = log.channel_names[c];
          if (std::find(reached.begin(), reached.end(), name) != reached.end()) continue;
          double m = 0;
          for (size_t j = 0; j < idx.size(); ++j) m = std::max(m, std::fabs(dfdp(ch, j)) * scales[j]);
          if (m > 1e-9) reached.push_back(name);
        }
      }
    }
  }
  return reached;
}

}  // namespace

nlohmann::json CandidateScore::ToJson() const {
  nlohmann::json j = {{"effect", effect},
                      {"round", round},
                      {"statistic", statistic},
                      {"test", "F(q, N - P1) on the noise-weighted RSS of a joint refit"},
                      {"p_value", p_value},
                      {"p_corrected", p_corrected},
                      {"correction", "Holm"},
                      {"passes", passes},
                      {"testable", testable},
                      {"channels", channels},
                      {"reason", reason},
                      {"num_parameters", num_parameters},
                      {"rss_before", rss_before},
                      {"rss_after", rss_after},
                      {"num_residuals", num_residuals},
                      {"num_free_parameters", num_free_parameters}};
  if (!testable) j["why_not_testable"] = why_not_testable;
  if (testable) {
    nlohmann::json est = nlohmann::json::object();
    for (const auto& spec : EffectLibrary()[EffectIndex(effect)].parameters) {
      const std::string name = effect + "." + spec.name;
      nlohmann::json e = {{"value", parameters.Value(name)}};
      for (size_t k = 0; k < identifiability.names.size(); ++k) {
        if (identifiability.names[k] == name) {
          e["std"] = identifiability.identifiable[k] ? nlohmann::json(identifiability.std[k])
                                                     : nlohmann::json(nullptr);
        }
      }
      est[name] = e;
    }
    j["estimates"] = est;
  }
  return j;
}

double WeightedRss(const std::vector<EstimationLog>& logs,
                   const std::vector<Eigen::MatrixXd>& model, const NoiseWeights& noise,
                   int* count) {
  double rss = 0;
  int n = 0;
  for (size_t i = 0; i < logs.size(); ++i) {
    for (int c = 0; c < logs[i].NumChannels(); ++c) {
      const double s = noise.For(logs[i].channel_names[c]);
      for (int k = 0; k < logs[i].NumRows(); ++k) {
        const double r = (logs[i].values(k, c) - model[i](k, c)) / s;
        if (std::isfinite(r)) {
          rss += r * r;
          ++n;
        }
      }
    }
  }
  if (count) *count = n;
  return rss;
}

Vehicle CandidateVehicle(const Vehicle& vehicle, const std::string& effect) {
  std::map<std::string, ParameterOverride> overrides;
  for (const auto& spec : EffectLibrary()[EffectIndex(effect)].parameters) {
    ParameterOverride o;
    o.estimated = true;
    // ground_effect's default k_ge = 1 is the physical value, not absence.
    if (effect == "ground_effect") o.value = 0.0;
    overrides[spec.name] = o;
  }
  return WithEffect(vehicle, effect, overrides);
}

std::vector<CandidateScore> ScoreCandidates(const Vehicle& vehicle, const OutputErrorResult& fit,
                                            const std::vector<EstimationLog>& logs,
                                            const OutputErrorOptions& fit_options, double alpha,
                                            int round,
                                            const std::function<void(const std::string&)>& progress) {
  const std::vector<std::string> present = vehicle.EffectNames();
  Vehicle fitted = vehicle;
  fitted.parameters = fit.parameters;
  int n0 = 0;
  const double rss0 = WeightedRss(logs, fit.predictions, fit.noise, &n0);

  OutputErrorOptions o = fit_options;
  o.noise = fit.noise;
  o.noise_relaxations = 0;
  o.segment_schedule_s = {fit_options.segment_schedule_s.back()};
  // A truncated refit only understates the RSS drop, so the cap keeps the
  // test conservative; the balance model converges in a few iterations, the
  // flight model's refits are the cost of a run (~1 s per iteration on 8 s of
  // 200 Hz flight, measured).
  o.max_iterations = std::min(o.max_iterations, 30);
  o.progress = nullptr;

  std::vector<CandidateScore> scores;
  for (const EffectInfo& info : EffectLibrary()) {
    if (std::find(present.begin(), present.end(), info.name) != present.end()) continue;
    CandidateScore s;
    s.effect = info.name;
    s.description = info.description;
    s.round = round;
    s.num_parameters = static_cast<int>(info.parameters.size());
    s.rss_before = rss0;
    s.rss_after = rss0;
    s.num_residuals = n0;
    const Vehicle candidate = CandidateVehicle(fitted, info.name);
    s.channels = ReachedChannels(candidate, info.name, logs, fit.noise);
    s.reason = info.description;
    if (s.channels.empty()) {
      s.why_not_testable =
          "no channel of these logs depends on its parameters (e.g. no motion, or no height, in "
          "a balance log)";
      s.reason += "; it cannot show in these logs";
      scores.push_back(s);
      continue;
    }
    std::string list;
    for (const std::string& c : s.channels) list += (list.empty() ? "" : ", ") + c;
    s.reason += "; it would show in " + list;
    const auto t0 = std::chrono::steady_clock::now();
    const OutputErrorResult r = FitOutputError(candidate, logs, o);
    if (progress) {
      progress("  refit with " + info.name + ": " + std::to_string(r.iterations) + " iterations, " +
               std::to_string(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()) + " s");
    }
    if (!r.usable) {
      s.why_not_testable = "the refit with it failed: " + r.why_not_usable;
      scores.push_back(s);
      continue;
    }
    s.testable = true;
    s.parameters = r.parameters;
    s.identifiability = r.identifiability;
    int n1 = 0;
    s.rss_after = WeightedRss(logs, r.predictions, fit.noise, &n1);
    s.num_free_parameters = static_cast<int>(r.parameters.FreeIndices().size());
    const double dof2 = std::max(1, n1 - s.num_free_parameters);
    const double drop = s.rss_before - s.rss_after;
    s.statistic = drop > 0 ? (drop / s.num_parameters) / (s.rss_after / dof2) : 0.0;
    s.p_value = FSurvival(s.statistic, s.num_parameters, dof2);
    scores.push_back(s);
  }
  // Holm: sort the tested p-values ascending; the i-th (0-based) of m is
  // compared with alpha / (m - i), monotone.
  std::vector<CandidateScore*> tested;
  for (CandidateScore& s : scores) {
    if (s.testable) tested.push_back(&s);
  }
  std::sort(tested.begin(), tested.end(), [](const CandidateScore* a, const CandidateScore* b) {
    if (a->p_value != b->p_value) return a->p_value < b->p_value;
    return a->statistic > b->statistic;
  });
  const int m = static_cast<int>(tested.size());
  double running = 0;
  for (int i = 0; i < m; ++i) {
    running = std::max(running, std::min(1.0, (m - i) * tested[i]->p_value));
    tested[i]->p_corrected = running;
    tested[i]->passes = running < alpha;
  }
  std::stable_sort(scores.begin(), scores.end(),
                   [](const CandidateScore& a, const CandidateScore& b) {
                     if (a.passes != b.passes) return a.passes;
                     if (a.testable != b.testable) return a.testable;
                     if (a.p_value != b.p_value) return a.p_value < b.p_value;
                     return a.statistic > b.statistic;
                   });
  return scores;
}

}  // namespace coaxid
