#include "ident/discover/candidate_scores.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/errors.h"
#include "core/report_values.h"
#include "core/stopwatch.h"
#include "dynamics/effects/effect_library.h"
#include "dynamics/model_jacobian.h"
#include "dynamics/outputs.h"
#include "ident/discover/residual_analysis.h"

namespace coaxid {

std::vector<std::string> EffectParameterNames(const std::string& effect) {
  std::vector<std::string> out;
  for (const auto& spec : EffectLibrary()[EffectIndex(effect)].parameters) {
    out.push_back(effect + "." + spec.name);
  }
  return out;
}

namespace {

std::vector<std::string> AllParameterNames(const std::vector<std::string>& effects) {
  std::vector<std::string> out;
  for (const std::string& e : effects) {
    for (const std::string& n : EffectParameterNames(e)) out.push_back(n);
  }
  return out;
}

// Holm's step-down correction over the testable scores: the i-th smallest
// (0-based) of m p-values is compared with alpha / (m - i), kept monotone.
void HolmCorrect(std::vector<CandidateScore>* scores, double alpha) {
  std::vector<CandidateScore*> tested;
  for (CandidateScore& s : *scores) {
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
}

// The vehicle to linearise: what the fit held stays held (the scale member
// of a flight-only fit, the parameters it left at a bound).
Vehicle AsTheFitHeldIt(Vehicle v, const OutputErrorResult& fit) {
  std::vector<std::string> held = ParametersAtBounds(fit.parameters);
  if (!fit.gauge.held_member.empty()) held.push_back(fit.gauge.held_member);
  for (const std::string& name : held) {
    if (v.parameters.Has(name)) v.parameters.SetEstimated(name, false);
  }
  return v;
}

}  // namespace

// |dy/dp| * scale above 1e-3 noise std at some sampled row.
std::vector<std::string> ChannelsReachedBy(const Vehicle& v,
                                           const std::vector<std::string>& parameters,
                                           const std::vector<EstimationLog>& logs,
                                           const NoiseWeights& noise) {
  std::vector<int> idx;
  std::vector<double> scales;
  for (const std::string& name : parameters) {
    const int i = v.parameters.IndexOrThrow(name);
    idx.push_back(i);
    scales.push_back(v.parameters[i].scale);
  }
  const Eigen::VectorXd theta = v.parameters.Values();
  std::vector<std::string> reached;
  const InputVector lag = v.model.InputLags(theta.data());
  for (const EstimationLog& log : logs) {
    const int n = log.NumRows();
    const int step = std::max(1, n / 400);
    const std::vector<HeldInput> held = log.kind == LogKind::kFlight
                                            ? HeldInputs(log.inputs, lag)
                                            : std::vector<HeldInput>();
    for (int k = 0; k < n; k += step) {
      Eigen::MatrixXd dydp;
      bool ok;
      if (log.kind == LogKind::kBalance) {
        double y[kNumBalanceChannels];
        ok = BalanceOutputJacobians(v.model, theta, log.inputs.input(k), idx, y, &dydp);
      } else {
        // Effect states (a bar's tilt) at 0.01: their parameters act through them.
        const Eigen::VectorXd x = v.model.StateOf(InitialStateFromLog(log, k), 0.01);
        double y[kNumFlightChannels];
        ok = FlightOutputJacobians(v.model, theta, x.data(), held[k], idx, y, nullptr,
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
        const Eigen::VectorXd x = v.model.StateOf(InitialStateFromLog(log, k), 0.01);
        Eigen::MatrixXd dfdx, dfdp;
        if (!DerivativeJacobians(v.model, theta, x.data(), held[k], held[k].t0, idx, &dfdx,
                                 &dfdp)) {
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

nlohmann::json CandidateScore::ToJson() const {
  nlohmann::json j = {
      {"effect", effect},
      {"round", round},
      {"statistic", statistic},
      {"test",
       "score test of the nested model linearised at the current fit, cluster-robust (Hotelling "
       "T^2 over segments / holds): F(q, M - q)"},
      {"p_value", p_value},
      {"p_corrected", p_corrected},
      {"correction", "Holm"},
      {"passes", passes},
      {"testable", testable},
      {"channels", channels},
      {"reason", reason},
      {"num_parameters", num_parameters},
      {"clusters", clusters},
      {"covariance_dof", covariance_dof},
      {"white_noise_statistic", white_statistic},
      {"white_noise_p_value", white_p_value},
      {"rss_before", rss_before},
      {"rss_after", rss_after},
      {"bic_change", bic_change},
      {"predicted_share_of_excess", predicted_share},
      {"num_residuals", num_residuals},
      {"num_free_parameters", num_free_parameters}};
  if (!testable) j["why_not_testable"] = why_not_testable;
  j["blind_at_bounds"] = blind_at_bounds;
  if (!beside.empty()) j["beside"] = beside;
  if (!added_with.empty()) j["added_with"] = added_with;
  if (!restart_values.empty()) j["restart_values"] = restart_values;
  if (!refit_starts.empty()) {
    auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
    nlohmann::json starts = nlohmann::json::array();
    for (const RefitStart& r : refit_starts) {
      starts.push_back({{"from", r.from},
                        {"cost", number(r.cost)},
                        {"weighted_rss", number(r.weighted_rss)},
                        {"kept", r.kept},
                        {"seconds", r.seconds}});
    }
    j["refit_starts"] = starts;
  }
  if (testable) {
    j["linearised_estimates"] = linearised_estimates;
    j["beyond_linear_range"] = beyond_linear_range;
  }
  if (refitted) {
    j["refit"] = {{"wald_statistic", wald_statistic},
                  {"wald_p_value", wald_p_value},
                  {"plausible", plausible},
                  {"share_of_excess_removed", share_of_excess},
                  {"share_of_excess_removed_held_out",
                   std::isfinite(share_of_excess_held_out)
                       ? nlohmann::json(share_of_excess_held_out)
                       : nlohmann::json(nullptr)},
                  {"excess_removed_per_channel", excess_removed},
                  {"channels_excess", channels_excess},
                  {"excess_removed_all_channels", excess_removed_all_channels},
                  {"significant", significant},
                  {"confirmed", confirmed}};
    if (!plausible) j["refit"]["why_implausible"] = why_implausible;
    if (!confirmed) j["refit"]["why_not_confirmed"] = why_not_confirmed;
    // A refit that failed has no estimates (why_not_confirmed says why).
    nlohmann::json est = nlohmann::json::object();
    for (const std::string& name : EffectParameterNames(effect)) {
      if (!parameters.Has(name)) continue;
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
  } else if (!why_not_confirmed.empty()) {
    j["why_not_refitted"] = why_not_confirmed;
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
    // Where absence has no derivative (a lag at T = 0), just beside it.
    if (std::isfinite(spec.linearise_at)) o.value = spec.linearise_at;
    overrides[spec.name] = o;
  }
  return WithEffect(vehicle, effect, overrides);
}

CandidatePass LinearisePass(const Vehicle& fitted, const OutputErrorResult& fit,
                            const std::vector<EstimationLog>& logs,
                            const OutputErrorOptions& fit_options) {
  const auto t0 = std::chrono::steady_clock::now();
  CandidatePass pass;
  pass.fitted = fitted;
  pass.fit = fit;
  const std::vector<std::string> present = fitted.EffectNames();
  Vehicle augmented = AsTheFitHeldIt(fitted, fit);
  std::map<std::string, double> absent;  // parameters linearised beside absence
  for (const EffectInfo& info : EffectLibrary()) {
    if (std::find(present.begin(), present.end(), info.name) != present.end()) continue;
    pass.candidates.push_back(info.name);
    augmented = CandidateVehicle(augmented, info.name);
    for (const auto& spec : info.parameters) {
      if (std::isfinite(spec.linearise_at)) absent[info.name + "." + spec.name] = spec.value;
    }
  }
  std::vector<int> cluster_rows;
  for (size_t i = 0; i < logs.size(); ++i) {
    cluster_rows.push_back(logs[i].kind == LogKind::kFlight
                               ? ClusterRows(logs[i], fit.predictions[i])
                               : 1);
  }
  std::string why;
  if (!LineariseFit(augmented, logs, fit.segments, fit.noise, cluster_rows, fit_options, absent,
                    &pass.linearised, &why)) {
    throw ComputationError("linearising the fit for the candidate tests: " + why);
  }
  pass.seconds = SecondsSince(t0);
  return pass;
}

std::vector<CandidateScore> ScoreCandidates(const CandidatePass& pass,
                                            const std::vector<EstimationLog>& logs,
                                            double alpha, int round, double weighted_excess) {
  const LinearisedFit& lin = pass.linearised;
  int n0 = 0;
  const double rss0 = WeightedRss(logs, pass.fit.predictions, pass.fit.noise, &n0);
  // Under the null every candidate is absent: the nuisance columns are the
  // segment states and the model's own free parameters.
  const ColumnTester tester(lin, ParametersExcept(lin, AllParameterNames(pass.candidates)));
  const int num_free = static_cast<int>(pass.fitted.parameters.FreeIndices().size());

  std::vector<CandidateScore> scores;
  for (const std::string& effect : pass.candidates) {
    const EffectInfo& info = EffectLibrary()[EffectIndex(effect)];
    CandidateScore s;
    s.effect = effect;
    s.description = info.description;
    s.round = round;
    s.num_parameters = static_cast<int>(info.parameters.size());
    s.rss_before = rss0;
    s.rss_after = rss0;
    s.num_residuals = n0;
    s.num_free_parameters = num_free + s.num_parameters;
    const Vehicle candidate = CandidateVehicle(pass.fitted, effect);
    const std::vector<std::string> names = EffectParameterNames(effect);
    s.channels = ChannelsReachedBy(candidate, names, logs, pass.fit.noise);
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
    const ColumnTest t = tester.Test(ParameterIndices(lin, names));
    s.clusters = t.clusters;
    s.covariance_dof = t.covariance_dof;
    if (!t.ok) {
      s.why_not_testable = t.why_not;
      scores.push_back(s);
      continue;
    }
    s.testable = true;
    s.statistic = t.statistic;
    s.p_value = t.p_value;
    s.white_statistic = t.white_statistic;
    s.white_p_value = t.white_p_value;
    // The drop is at most lin.rss (ColumnTester); rss0 leaves out the
    // continuity ties, so clamp at 0.
    s.rss_after = std::max(0.0, rss0 - t.predicted_rss_drop);
    s.bic_change = s.num_parameters * std::log(static_cast<double>(n0)) - t.predicted_rss_drop;
    s.predicted_share = weighted_excess > 0 ? t.predicted_rss_drop / weighted_excess : 0.0;
    for (size_t k = 0; k < names.size(); ++k) {
      const Parameter& p = candidate.parameters.Get(names[k]);
      const double value = p.value + t.step[k] * lin.parameter_scales[lin.ParameterIndex(names[k])];
      if (value < p.lower || value > p.upper) s.beyond_linear_range = true;
      s.linearised_estimates[names[k]] = std::clamp(value, p.lower, p.upper);
    }
    scores.push_back(s);
  }
  HolmCorrect(&scores, alpha);
  std::stable_sort(scores.begin(), scores.end(),
                   [](const CandidateScore& a, const CandidateScore& b) {
                     if (a.passes != b.passes) return a.passes;
                     if (a.testable != b.testable) return a.testable;
                     // Among passing candidates the cluster-robust p saturates at a
                     // few clusters' worth of evidence: the best is the one that
                     // explains the most of the residual for its parameters.
                     if (a.passes && a.bic_change != b.bic_change) return a.bic_change < b.bic_change;
                     if (a.p_value != b.p_value) return a.p_value < b.p_value;
                     return a.statistic > b.statistic;
                   });
  return scores;
}

bool ReachesAny(const std::vector<std::string>& channels, const std::vector<std::string>& of) {
  return std::any_of(channels.begin(), channels.end(), [&](const std::string& c) {
    return std::find(of.begin(), of.end(), c) != of.end();
  });
}

std::vector<PlausibilityFinding> FarOutsidePhysicalRange(const ParameterSet& fit,
                                                         const ParameterSet& declared) {
  std::map<std::string, double> estimates;
  for (int i : fit.FreeIndices()) {
    if (declared.Has(fit[i].name)) estimates[fit[i].name] = fit[i].value;
  }
  std::vector<PlausibilityFinding> out;
  for (const PlausibilityFinding& f :
       JudgePlausibility(declared, estimates, nullptr, nullptr).findings) {
    if (f.kind != PlausibilityFinding::Kind::kOutsidePhysicalRange || !estimates.count(f.subject)) {
      continue;
    }
    const bool far_above = f.upper > 0 && f.value > kFarOutsidePhysicalRange * f.upper;
    const bool far_below = f.lower > 0 && f.value < f.lower / kFarOutsidePhysicalRange;
    if (far_above || far_below) out.push_back(f);
  }
  // The inertias' triangle inequality names no one parameter: when the
  // largest principal moment is kFarOutsidePhysicalRange times the sum of the
  // other two, each of the three lies that far outside the range the other
  // two leave it, [|a - b|, a + b]. Measured: the four fresh runs whose final
  // model broke it that far (of 400, judged 2026-11-29) had all missed or
  // added the wrong effect (9524: Ixx 80 x Iyy + Izz, gyroscopic missed;
  // restarted off there, it is found), the rest broke it by at
  // most 1.5 x, as the study's randomised truths (Ixx, Iyy 30 % apart, Izz
  // small) do themselves.
  const char* inertias[] = {"Ixx", "Iyy", "Izz"};
  double largest = 0, sum = 0;
  for (const char* I : inertias) {
    largest = std::max(largest, fit.Value(I));
    sum += fit.Value(I);
  }
  if (largest > kFarOutsidePhysicalRange * (sum - largest)) {
    for (int k = 0; k < 3; ++k) {
      const std::string c = inertias[k], a = inertias[(k + 1) % 3], b = inertias[(k + 2) % 3];
      const bool listed = std::any_of(out.begin(), out.end(),
                                      [&](const PlausibilityFinding& g) { return g.subject == c; });
      if (!estimates.count(c) || listed) continue;
      PlausibilityFinding f;
      f.kind = PlausibilityFinding::Kind::kOutsidePhysicalRange;
      f.subject = c;
      f.value = fit.Value(c);
      f.lower = std::abs(fit.Value(a) - fit.Value(b));
      f.upper = fit.Value(a) + fit.Value(b);
      f.text = c + " = " + NumberText(f.value) + " kg m^2 lies outside [|" + a + " - " + b +
               "|, " + a + " + " + b + "] = [" + NumberText(f.lower) + ", " +
               NumberText(f.upper) +
               "] kg m^2 (principal moments of inertia obey the triangle inequality)";
      out.push_back(f);
    }
  }
  return out;
}

std::vector<std::string> SymptomaticParameters(const ParameterSet& fit, const ParameterSet& declared) {
  std::vector<std::string> out = ParametersAtBounds(fit);
  for (const PlausibilityFinding& f : FarOutsidePhysicalRange(fit, declared)) {
    if (std::find(out.begin(), out.end(), f.subject) == out.end()) out.push_back(f.subject);
  }
  return out;
}

std::map<std::string, double> ConfigValuesOfSymptomaticParameters(const ParameterSet& fit,
                                                                  const Vehicle& declared) {
  std::map<std::string, double> out;
  for (const std::string& name : SymptomaticParameters(fit, declared.parameters)) {
    if (!declared.parameters.Has(name)) continue;  // an added effect's parameter
    const Parameter& p = fit.Get(name);
    const double config = declared.parameters.Value(name);
    if (config > p.lower && config < p.upper) out[name] = config;
  }
  return out;
}

// Restarts only the parameters whose channels the candidate reaches from
// there: restarting every parameter at a bound (Ixx at 50 x its value on a
// flight-only log) left the right candidate's refit worse than its warm start.
// A candidate that already reaches those channels restarts them too: from the
// bound its refit stays in the declared fit's basin (measured: an undeclared
// CG offset with a balance log, d pressed to its lower bound and Iyy to its
// upper one so that the swashplate's trim moment vanishes; the cg_offset
// refit from there was never tried, from the config it is the right model;
// an undeclared swashplate bias, low flight, flight only, sigma0 and Cy at
// bounds: the passing swashplate_bias refitted from there stayed
// insignificant, from the config values it is found).
void MarkRestartsAtBounds(const Vehicle& fitted, const Vehicle& declared,
                          const std::map<std::string, std::vector<std::string>>& distorted,
                          const std::vector<EstimationLog>& logs, const NoiseWeights& noise,
                          std::vector<CandidateScore>* scores) {
  const std::map<std::string, double> configs =
      ConfigValuesOfSymptomaticParameters(fitted.parameters, declared);
  for (const auto& [name, channels] : distorted) {
    const auto at = configs.find(name);
    if (at == configs.end()) continue;
    const double config = at->second;
    Vehicle inside = fitted;
    inside.parameters.SetValue(name, config);
    for (CandidateScore& s : *scores) {
      if (s.testable && ReachesAny(s.channels, channels)) {
        s.restart_values[name] = config;
        continue;
      }
      const std::vector<std::string> reached = ChannelsReachedBy(
          CandidateVehicle(inside, s.effect), EffectParameterNames(s.effect), logs, noise);
      const bool newly = std::any_of(reached.begin(), reached.end(), [&](const std::string& c) {
        return ReachesAny({c}, channels) && !ReachesAny({c}, s.channels);
      });
      if (!newly) continue;
      s.blind_at_bounds = true;
      s.restart_values[name] = config;
      for (const std::string& c : reached) {
        if (!ReachesAny({c}, s.channels)) s.channels.push_back(c);
      }
    }
  }
}

namespace {

// A solve near the current fit: the final segment length, each segment
// starting on the current fit's trajectory, at its noise weights, kept.
OutputErrorOptions WarmOptions(const OutputErrorOptions& fit_options, const Vehicle& current,
                               const OutputErrorResult& current_fit) {
  OutputErrorOptions o = fit_options;
  o.noise = current_fit.noise;
  o.noise_relaxations = 0;
  o.segment_schedule_s = {fit_options.segment_schedule_s.back()};
  o.start_segments = current_fit.segments;
  o.start_segment_state_names = current.model.StateNames();
  // A fit that needed the scale held in the solve (its scale-free solution
  // wanted a member beyond its bounds) is refitted with it held: the
  // scale-free solve from its neighbourhood fails the same move again, and
  // the fallback then solves once more from the same start (measured,
  // swashplate_bias truth, flight only, 53 s: 12 such failed solves took
  // 30 of the run's 116 s of CPU, every one of them thrown away).
  if (current_fit.scale_held_in_solve) o.scale_free_in_solve = false;
  return o;
}

}  // namespace

OutputErrorResult WarmRefit(const Vehicle& vehicle, const std::vector<EstimationLog>& logs,
                            const OutputErrorOptions& fit_options, const Vehicle& current,
                            const OutputErrorResult& current_fit, bool coarse_to_fine) {
  OutputErrorOptions o = WarmOptions(fit_options, current, current_fit);
  if (coarse_to_fine) {
    o.segment_schedule_s = fit_options.segment_schedule_s;
    o.start_segments.clear();
    o.start_segment_state_names.clear();
  }
  OutputErrorResult refit = FitOutputError(vehicle, logs, o);
  if (!refit.usable && refit.scale_move_failed) {
    // Flight-only: the solve drifted along the scale line, out of the
    // bounds once moved back onto the held member (measured: a motor_lag
    // refit wanted gamma1 = 1.1e-4, 94 x its fit). The declared fit's
    // fallback: hold the scale in the solve, so a member meets its bound.
    o.scale_free_in_solve = false;
    refit = FitOutputError(vehicle, logs, o);
  }
  return refit;
}

namespace {

// Where a candidate's refit starts: the effect at its Gauss-Newton step
// (inside the bounds) and every other parameter at the current fit; or, with
// declared parameters restarted (`restarts`, config values), the effect at
// absence. A one-sided parameter (absent at its bound: k_ge, J_r, k_T >= 0)
// whose step points out of the bounds, or that starts at absence, would start
// pinned there, where a bounded solver need not leave it (measured: an
// undeclared ground effect's k_ge stayed at 0 while Cz sat at its bound): it
// starts at the library's typical strength instead. A candidate whose refit
// restarts declared parameters has no step to start from: blind at the
// bounds, its columns vanish there; otherwise the step was taken at the
// distorted point.
Vehicle CandidateStart(const CandidatePass& pass, const CandidateScore& score,
                       const std::map<std::string, double>& restarts, bool from_step) {
  Vehicle candidate = CandidateVehicle(pass.fitted, score.effect);
  const auto& specs = EffectLibrary()[EffectIndex(score.effect)].parameters;
  for (const auto& spec : specs) {
    const std::string name = score.effect + "." + spec.name;
    const auto it = score.linearised_estimates.find(name);
    if (from_step && it == score.linearised_estimates.end()) continue;
    const Parameter& p = candidate.parameters.Get(name);
    const double step = from_step ? it->second : p.value;
    // A lag linearised beside absence (linearise_at) is one-sided too.
    const bool absent_at_lower = p.value == p.lower || std::isfinite(spec.linearise_at);
    const bool pinned_at_absence =
        (absent_at_lower && step <= p.lower) || (p.value == p.upper && step >= p.upper);
    candidate.parameters.SetValue(
        name, pinned_at_absence ? std::clamp(std::fabs(spec.typical), p.lower, p.upper) : step);
  }
  for (const auto& [name, value] : restarts) candidate.parameters.SetValue(name, value);
  return candidate;
}

// The fit of `model` (`fit`) with its noise weights re-estimated once from
// its residuals and solved again, warm from the fit (an output-error
// relaxation), when fit_options.noise_relaxations allows one and the weights
// move by more than its tolerance. True if *fit was replaced. A fit that
// stopped at its iteration cap is first continued at its own weights (the
// relaxation of FitOutputError: measured, undeclared stabilizer bar with the
// balance log, the wind refit's share went 28 % -> 63 % with those 20
// iterations); a converged one takes the new weights from its predictions
// and solves once.
bool Reweighted(const Vehicle& model, const std::vector<EstimationLog>& logs,
                const OutputErrorOptions& fit_options, OutputErrorResult* fit) {
  if (fit_options.noise_relaxations < 1 || !fit->usable) return false;
  OutputErrorOptions o = WarmOptions(fit_options, model, *fit);
  if (fit->hit_iteration_limit) {
    o.noise_relaxations = 1;
  } else {
    o.noise = NoiseFromPredictions(logs, fit->predictions);
    if (MaxRelativeChange(fit->noise, o.noise) < fit_options.noise_relaxation_tolerance) {
      return false;
    }
    o.noise_relaxations = 0;
  }
  Vehicle v = model;
  v.parameters = fit->parameters;
  OutputErrorResult relaxed = FitOutputError(v, logs, o);
  // Weights that moved less than the tolerance were not applied: no change.
  if (!relaxed.usable || relaxed.noise.std == fit->noise.std) return false;
  *fit = std::move(relaxed);
  return true;
}

// "Ixx, Iyy": the restarted parameters' names.
std::string RestartedNames(const std::map<std::string, double>& restarts) {
  std::string names;
  for (const auto& [name, value] : restarts) names += (names.empty() ? "" : ", ") + name;
  return names;
}

std::string StartText(const std::map<std::string, double>& restarts, bool from_step) {
  if (from_step) return "its linearised step, the rest at the current fit";
  return restarts.empty() ? "absence, the rest at the current fit"
                          : "absence, " + RestartedNames(restarts) + " at the config values";
}

}  // namespace

bool OwnParameterAtBound(const std::string& effect, const ParameterSet& parameters) {
  const std::vector<std::string> names = EffectParameterNames(effect);
  for (const std::string& name : ParametersAtBounds(parameters)) {
    if (std::find(names.begin(), names.end(), name) != names.end()) return true;
  }
  return false;
}

ColumnTest EffectWaldTest(const CandidatePass& at_refit, const std::string& effect,
                          std::string* why_not) {
  const LinearisedFit& lin = at_refit.linearised;
  const std::vector<std::string> names = EffectParameterNames(effect);
  std::vector<std::string> excluded = AllParameterNames(at_refit.candidates);
  excluded.insert(excluded.end(), names.begin(), names.end());
  const ColumnTester tester(lin, ParametersExcept(lin, excluded));
  // Scaled distance from absence (every effect's absent value is 0).
  std::vector<std::string> tested;
  for (const std::string& name : names) {
    if (lin.ParameterIndex(name) >= 0) tested.push_back(name);
  }
  if (tested.empty()) {
    *why_not = "every parameter of it sits at a bound";
    return ColumnTest();
  }
  Eigen::VectorXd values(tested.size());
  for (size_t k = 0; k < tested.size(); ++k) {
    values[k] = at_refit.fitted.parameters.Value(tested[k]) /
                lin.parameter_scales[lin.ParameterIndex(tested[k])];
  }
  ColumnTest t = tester.Test(ParameterIndices(lin, tested), &values);
  if (!t.ok) *why_not = t.why_not;
  return t;
}

bool RefitCandidate(const CandidatePass& pass, const std::vector<EstimationLog>& logs,
                    const OutputErrorOptions& fit_options,
                    const std::map<std::string, double>& declared_at_bounds,
                    CandidateScore* score, OutputErrorResult* refit, CandidatePass* next,
                    const ReweightingGate& reweighting) {
  score->refitted = true;
  // The other parameters start at the current fit, every declared one free
  // (a bound the declared fit pressed one against may let go). Restarted
  // ones are far from it: the whole coarse-to-fine schedule (measured: an
  // undeclared CG offset, d and Iyy restarted from their bounds, 1 s segments
  // alone stopped at cg_offset = 0 and 7 x the declared fit's excess; the
  // schedule finds the truth).
  const bool restarts = !score->restart_values.empty();
  auto t_start = std::chrono::steady_clock::now();
  *refit = WarmRefit(CandidateStart(pass, *score, score->restart_values, !restarts), logs,
                     fit_options, pass.fitted, pass.fit, restarts);
  int n1 = 0;
  auto start_of = [&](const OutputErrorResult& r, const std::string& from) {
    RefitStart s{from, r.usable ? r.final_cost : INFINITY,
                 r.usable ? WeightedRss(logs, r.predictions, pass.fit.noise, &n1) : INFINITY,
                 true, SecondsSince(t_start)};
    t_start = std::chrono::steady_clock::now();
    return s;
  };
  score->refit_starts.push_back(start_of(*refit, StartText(score->restart_values, !restarts)));
  // The candidate's model holds the current one (at absence it is the
  // current fit), and the refit minimises the same objective at the same
  // weights (output and continuity residuals): one that ends above the
  // current fit's objective is short of its optimum, not a sign that the
  // effect is absent (measured, undeclared CG offset, flight only: the
  // refit with Iyy restarted ended 0.2 % of the excess worse than the
  // declared fit and was rejected as insignificant). Nor is a refit that
  // ends with the effect at a bound while declared parameters sit at theirs
  // conclusive (measured, undeclared stabilizer bar and swashplate bias,
  // flight only: Ixx and Iyy at their upper bounds, the bar's refit from
  // there ended at T_b = 10). Either way the refit runs again from the other
  // start (restarted at the config values <-> at the current fit) and the
  // lower objective is kept.
  const bool above_current = !(score->refit_starts.back().cost <=
                               pass.fit.final_cost * (1 + 10 * fit_options.function_tolerance));
  const bool at_bound_beside_bounds = refit->usable && !declared_at_bounds.empty() &&
                                      OwnParameterAtBound(score->effect, refit->parameters);
  // A candidate that passes its score test has a step worth starting from
  // even when its refit restarts declared parameters: the restart may end
  // below the current fit yet in a poorer basin (measured, undeclared
  // swashplate bias with the balance log, Iyy at its bound: restarted, its
  // refit removed 20 % of the excess).
  const bool passing_restart = restarts && score->passes;
  if (above_current || at_bound_beside_bounds || passing_restart) {
    const std::map<std::string, double> other = restarts ? std::map<std::string, double>()
                                                         : declared_at_bounds;
    // From a restart, the other start is the linearised step at the fit;
    // from the step, the declared parameters at bounds restarted (or, with
    // none, the effect at absence: exactly the current fit).
    OutputErrorResult second = WarmRefit(CandidateStart(pass, *score, other, restarts), logs,
                                         fit_options, pass.fitted, pass.fit, !other.empty());
    RefitStart s2 = start_of(second, StartText(other, restarts));
    s2.kept = s2.cost < score->refit_starts.back().cost;
    score->refit_starts.back().kept = !s2.kept;
    score->refit_starts.push_back(s2);
    if (s2.kept) *refit = std::move(second);
  }
  // Every start ended well above the current fit's objective (a failed
  // solve, not a near tie), and none was the current fit itself (the effect
  // at absence, nothing restarted): the refit runs from there too, where it
  // can end no higher (measured, an undeclared CG offset with wind, flight
  // only, beta at its bound: the restart ended at 1.9 x the current fit's
  // cost and the linearised step at 280 x; the refit was reported to remove
  // -140 % of the excess). A one-sided effect starts at its typical strength
  // instead of absence (CandidateStart): near the current fit, not on it.
  const bool current_tried = score->refit_starts.size() > 1 && !restarts &&
                             declared_at_bounds.empty();
  double best = INFINITY;
  for (const RefitStart& r : score->refit_starts) best = std::min(best, r.cost);
  if (!(best <= 1.01 * pass.fit.final_cost) && !current_tried) {
    OutputErrorResult third = WarmRefit(CandidateStart(pass, *score, {}, false), logs,
                                        fit_options, pass.fitted, pass.fit, false);
    RefitStart s3 = start_of(third, StartText({}, false));
    s3.kept = s3.cost < best;
    if (s3.kept) {
      for (RefitStart& r : score->refit_starts) r.kept = false;
      *refit = std::move(third);
    }
    score->refit_starts.push_back(s3);
  }
  // No fourth start from the linearised step with the declared parameters
  // restarted too: it found seed 21453's stabilizer bar while the fits
  // integrated stiff trial points, and since they refuse them
  // (IntegratorOptions::stiff_holds_fail) it was kept in none of 49 refits
  // (240 judged runs, 112 timed logs) for about 1.4 s each
  // (docs/discover_confusion.md, thirty-fifth session).
  if (!refit->usable) {
    score->why_not_confirmed = "the joint refit failed: " + refit->why_not_usable;
    return false;
  }
  const std::vector<std::string> names = EffectParameterNames(score->effect);
  // The refit's estimates, and its parameters at a bound (implausible).
  auto take = [&](const OutputErrorResult& r) {
    score->parameters = r.parameters;
    score->identifiability = r.identifiability;
    score->rss_after = WeightedRss(logs, r.predictions, pass.fit.noise, &n1);
    score->plausible = true;
    score->why_implausible.clear();
    int at_bound = 0;
    for (const std::string& name : ParametersAtBounds(r.parameters)) {
      if (std::find(names.begin(), names.end(), name) == names.end()) continue;
      const Parameter& p = r.parameters.Get(name);
      ++at_bound;
      score->plausible = false;
      score->why_implausible += (score->why_implausible.empty() ? "" : "; ") + name + " = " +
                                std::to_string(p.value) + " at its bound [" +
                                std::to_string(p.lower) + ", " + std::to_string(p.upper) + "]";
    }
    return at_bound;
  };
  // Every parameter of the effect at a bound (absent, or pinned at a limit)
  // in a converged refit: re-estimating the noise weights would relax the
  // current model's fit, not test the effect, so it is decided here. A refit
  // stopped at its cap may still leave the bound (measured, undeclared
  // stabilizer bar with the balance log: gyroscopic's J_r did, and the
  // detour through it freed d from its bound).
  if (take(*refit) == static_cast<int>(names.size()) && !refit->hit_iteration_limit) {
    score->why_not_confirmed = "at the refit every parameter of it sits at a bound";
    return false;
  }
  // A refit that removes almost none of its channels' excess at the current
  // weights is not re-weighted (up to two more capped solves): the
  // re-weighting does not make it material (DiscoveryOptions::
  // min_share_to_reweight).
  if (reweighting.share) {
    const double share = reweighting.share(*refit);
    if (!(share >= reweighting.min_share)) {
      score->share_of_excess = share;
      score->why_not_confirmed =
          "practically insignificant: at the current noise weights its refit removes " +
          NumberText(100 * share, "%.1f") + " % of its channels' excess error, below " +
          NumberText(100 * reweighting.min_share, "%.0f") + " %: not re-weighted";
      return false;
    }
  }
  // The current fit's weights are inflated by a missing effect in the very
  // channels it reaches: the model with the candidate re-estimates them
  // once, as the declared fit did, and is judged at its own (measured,
  // undeclared CG offset, flight only: the refit at the current weights
  // removed 30 % of its channels' excess, reweighted 59 %).
  Vehicle candidate = CandidateVehicle(pass.fitted, score->effect);
  if (Reweighted(candidate, logs, fit_options, refit)) take(*refit);
  candidate.parameters = refit->parameters;
  CandidatePass at_refit = LinearisePass(candidate, *refit, logs, fit_options);
  std::string why_not_tested;
  const ColumnTest t = EffectWaldTest(at_refit, score->effect, &why_not_tested);
  if (!t.ok) {
    score->why_not_confirmed = "at the refit: " + why_not_tested;
    return false;
  }
  score->wald_statistic = t.statistic;
  score->wald_p_value = t.p_value;
  *next = std::move(at_refit);
  return true;
}

}  // namespace coaxid
