#include "ident/discover/discovery.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

#include "core/errors.h"
#include "core/report.h"
#include "core/report_values.h"
#include "core/stopwatch.h"
#include "ident/discover/practical_significance.h"
#include "ident/discover/round_choice.h"
#include "ident/discover/shortlist.h"
#include "ident/ekf/ekf_start.h"

namespace coaxid {
namespace {

using Clock = std::chrono::steady_clock;

void Say(const DiscoveryOptions& o, const std::string& line) {
  if (o.progress) o.progress(line);
}

// The held-out side of a snapshot (nothing without held-out logs).
void AddValidation(const std::vector<EstimationLog>& validation, const DiscoveryOptions& o,
                   ModelSnapshot* s) {
  if (validation.empty()) return;
  s->validation_predictions =
      PredictWithFixedParameters(s->vehicle, validation, s->result.noise, o.window_s, o.fit);
  s->validation = ChannelFitErrors(validation, s->validation_predictions);
  s->validation_residual_tests = AnalyseResiduals(validation, s->validation_predictions, o.residuals);
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
  AddValidation(validation, o, &s);
  return s;
}

// The Wald level of a round's refits: alpha over the number refitted.
double WaldLevel(const DiscoveryOptions& o, size_t refitted) {
  return o.alpha / static_cast<double>(std::max<size_t>(1, refitted));
}

// Why a refitted candidate fails a gate before practical significance (empty:
// none): the Wald test at `level`, physical meaning, an excess to remove.
std::string WhyNotSignificant(const CandidateScore& s, double level, const DiscoveryOptions& o) {
  if (!(s.wald_p_value < level)) {
    return "its parameters are not significantly away from absence at the refit (cluster-robust "
           "Wald p = " + NumberText(s.wald_p_value, "%.3g") + ", level " +
           NumberText(level, "%.3g") + ")";
  }
  if (!s.plausible) return "not physically meaningful: " + s.why_implausible;
  if (!(s.channels_excess >= o.min_channels_excess)) {
    return "its channels hold almost no excess error to remove (" +
           NumberText(s.channels_excess, "%.3g") + " noise variances, below " +
           NumberText(o.min_channels_excess, "%.3g") + ")";
  }
  return "";
}

// Why a refitted candidate is not added (empty: it is), at the Wald level
// `level`. Without a held-out share (NaN) the last gate reads the estimation
// share alone; the held-out share only ever adds a condition to that gate.
std::string WhyNotConfirmed(const CandidateScore& s, double level, const DiscoveryOptions& o) {
  const std::string why = WhyNotSignificant(s, level, o);
  if (!why.empty()) return why;
  const double share_held_out =
      std::isfinite(s.share_of_excess_held_out) ? s.share_of_excess_held_out : s.share_of_excess;
  if (!(s.share_of_excess >= o.min_share_of_excess && share_held_out >= o.min_share_of_excess)) {
    return "practically insignificant: it removes " +
           ShareText(s.share_of_excess, s.share_of_excess_held_out) + ", below " +
           NumberText(100 * o.min_share_of_excess, "%.0f") + " %";
  }
  return "";
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

// What a candidate's refit gives the loop: the model with it and the pass
// at the refit (the next round's, if it is added).
struct CandidateRefit {
  bool ok = false;
  double seconds = 0;
  double share_of_all_excess = 0;  // of the excess error over all channels, estimation data
  ModelSnapshot snapshot;
  CandidatePass next;
};

// Continues a fit that stopped at the loop's iteration cap, at most three
// more solves at the final segment length and the same noise weights, each
// from the fit's parameters and trajectory (WarmRefit): a
// candidate's refit judged against an unconverged fit is credited with the
// iterations, not the effect (measured, cg_offset truth, flight only: with
// cg_offset added after 20 iterations, the refits of wind and
// swashplate_bias "removed" 123 % and 115 % of the remaining excess, and
// swashplate_bias was added).
OutputErrorResult Converged(const Vehicle& model, OutputErrorResult fit,
                            const std::vector<EstimationLog>& logs,
                            const OutputErrorOptions& fit_options, const DiscoveryOptions& options) {
  Vehicle v = model;
  for (int k = 0; k < 3 && fit.hit_iteration_limit; ++k) {
    Say(options, "discover: the fit stopped at its " + std::to_string(fit_options.max_iterations) +
                     " iterations: continuing it");
    v.parameters = fit.parameters;
    // The same problem from where the fit stopped: with the parameters it
    // held at their bounds held, and from its trust region. Started afresh
    // (nothing held, Ceres' 1e4), the continuations of a fit that pressed Cz
    // and sigma0 on their bounds spent 5 of their 20 iterations in failed
    // steps finding them again (ground effect, flight only).
    OutputErrorOptions continued = fit_options;
    continued.start_held_at_bounds = fit.held_at_bounds;
    continued.initial_trust_region_radius = fit.trust_region_radius;
    OutputErrorResult next = WarmRefit(v, logs, continued, v, fit);
    if (!next.usable) break;
    fit = std::move(next);
  }
  return fit;
}

// A declared fit that left parameters at a bound may sit in a wrong basin
// rather than show a missing effect: the declared model refitted with those
// parameters restarted at their config values (the others at the fit),
// through the whole coarse-to-fine schedule, replaces it when its weighted
// RSS (the fit's noise weights) is lower. Measured (swashplate bias truth,
// low flight, flight only): sigma0 at its upper bound and Cy at 0; every
// candidate refitted with sigma0 restarted "removed" 58-62 % of the excess
// while its own parameters stayed insignificant: the restart, not the
// effect. The candidates are then judged against the better declared fit.
// The same holds for the model once an effect is added (measured, same
// flight: with swashplate_bias added, sigma0 and Cy still at their bounds,
// wind and rotor_drag refitted from their config values each "removed"
// 96 %, wind was added): `model` is the current model, `declared` gives the
// config values.
OutputErrorResult RestartedOffBounds(const Vehicle& model, const Vehicle& declared,
                                     OutputErrorResult fit, const std::vector<EstimationLog>& logs,
                                     const OutputErrorOptions& fit_options,
                                     const DiscoveryOptions& options, std::string* note) {
  Vehicle restarted = model;
  restarted.parameters = fit.parameters;
  std::string names;
  for (const auto& [name, config] : ConfigValuesOfSymptomaticParameters(fit.parameters, declared)) {
    restarted.parameters.SetValue(name, config);
    names += (names.empty() ? "" : ", ") + name;
  }
  if (names.empty()) return fit;
  Say(options, "discover: the fit left " + names +
                   " at a bound or far outside the physical range: refitting from their config values");
  OutputErrorResult refit = WarmRefit(restarted, logs, fit_options, model, fit, true);
  if (!refit.usable) return fit;
  int n = 0;
  const double before = WeightedRss(logs, fit.predictions, fit.noise, &n);
  const double after = WeightedRss(logs, refit.predictions, fit.noise, &n);
  char line[256];
  std::snprintf(line, sizeof line,
                "the fit restarted with %s at the config values: weighted RSS %.6g "
                "against %.6g%s",
                names.c_str(), after, before, after < before ? ": kept" : ": not kept");
  Say(options, std::string("discover: ") + line);
  if (!(after < before)) return fit;
  *note = line;
  return Converged(model, std::move(refit), logs, fit_options, options);
}

// Refits the shortlisted candidates side by side and judges each: Wald p
// below alpha over the number refitted (Bonferroni), no parameter at a bound,
// and at least min_share_of_excess of its channels' excess error removed on
// the estimation data and on the held-out data.
std::vector<CandidateRefit> RefitInParallel(const CandidatePass& pass,
                                            const std::vector<EstimationLog>& estimation,
                                            const std::vector<EstimationLog>& validation,
                                            const ModelSnapshot& now, const std::vector<int>& shortlist,
                                            const std::map<std::string, double>& declared_at_bounds,
                                            std::vector<CandidateScore>* scores,
                                            const DiscoveryOptions& o, Clock::time_point start) {
  const int n = static_cast<int>(shortlist.size());
  std::vector<CandidateRefit> refits(n);
  if (n == 0) return refits;
  std::string names;
  for (int k : shortlist) names += (names.empty() ? "" : ", ") + (*scores)[k].effect;
  Say(o, "discover: refitting " + names + " jointly (" +
             NumberText(SecondsSince(start), "%.1f s") + " so far)");
  // Each worker's fits and held-out predictions: its share of the threads,
  // silent (side by side: the loop reports each result).
  DiscoveryOptions worker_options = o;
  OutputErrorOptions& fit = worker_options.fit;
  fit.progress = nullptr;
  const int workers = std::max(1, std::min(n, o.fit.num_threads));
  fit.num_threads = std::max(1, o.fit.num_threads / workers);
  const double level = WaldLevel(o, shortlist.size());
  // The first (in shortlist order) refit that qualifies and removes at least
  // decisive_share_of_all_excess of the excess over all channels; the refits
  // ranked below it stop, whichever finished first, so the outcome does not
  // depend on the timing.
  std::atomic<int> decided_by{n};
  auto evaluate = [&](int k) {
    CandidateScore& s = (*scores)[shortlist[k]];
    OutputErrorResult refit;
    OutputErrorOptions fit_k = fit;
    fit_k.stop_requested = [&decided_by, k] { return decided_by.load() < k; };
    const bool usable = RefitCandidate(pass, estimation, fit_k, declared_at_bounds, &s, &refit,
                                       &refits[k].next);
    if (!usable || fit_k.stop_requested()) return;  // stopped: set aside below, unjudged
    Vehicle v = refits[k].next.fitted;
    refits[k].snapshot = Snapshot(v, refit, estimation, {}, o);
    const ExcessShare est = ShareOfExcessRemoved(now.fit, refits[k].snapshot.fit,
                                                 now.residual_tests, s.channels);
    s.share_of_excess = est.share;
    s.excess_removed = est.per_channel;
    s.channels_excess = est.excess;
    std::vector<std::string> all_channels;
    for (const ChannelResidualTest& t : now.residual_tests) all_channels.push_back(t.channel);
    const ExcessShare all = ShareOfExcessRemoved(now.fit, refits[k].snapshot.fit,
                                                 now.residual_tests, all_channels);
    s.excess_removed_all_channels = all.share * all.excess;
    refits[k].share_of_all_excess = all.share;
    // The held-out prediction (start states fitted per window) is the
    // costliest step after the refit (measured, a 30 s held-out flight under
    // a model missing three effects: 13 s in one of two workers, its cap of
    // 50 iterations), and it decides only a candidate that passes every gate
    // on the estimation data.
    if (!validation.empty() && WhyNotConfirmed(s, level, o).empty()) {
      AddValidation(validation, worker_options, &refits[k].snapshot);
      s.share_of_excess_held_out =
          ShareOfExcessRemoved(now.validation, refits[k].snapshot.validation,
                               now.validation_residual_tests, s.channels)
              .share;
    }
    refits[k].ok = true;
    if (all.share >= o.decisive_share_of_all_excess && WhyNotConfirmed(s, level, o).empty()) {
      int d = decided_by.load();
      while (k < d && !decided_by.compare_exchange_weak(d, k)) {  // the lowest k decides
      }
    }
  };
  auto one = [&](int k) {
    const auto t0 = Clock::now();
    evaluate(k);
    refits[k].seconds = SecondsSince(t0);
  };
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int k = next++; k < n; k = next++) {
      if (k <= decided_by.load()) one(k);
    }
  };
  std::vector<std::thread> threads;
  for (int w = 1; w < workers; ++w) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
  for (int k = 0; k < n; ++k) {
    CandidateScore& s = (*scores)[shortlist[k]];
    const int decider = decided_by.load();
    if (k > decider) {
      const std::string& effect = (*scores)[shortlist[decider]].effect;
      s.refitted = false;
      s.refit_starts.clear();
      s.confirmed = false;
      s.why_not_confirmed =
          "not judged: " + effect + ", ranked above it, qualifies and removes " +
          NumberText(100 * refits[decider].share_of_all_excess, "%.0f") +
          " % of the excess error over all channels; the next round tests it against the model "
          "with " + effect;
      refits[k].ok = false;
      Say(o, "  refit " + s.effect + ": " + s.why_not_confirmed);
      continue;
    }
    if (refits[k].ok) {
      s.significant = WhyNotSignificant(s, level, o).empty();
      const std::string why = WhyNotConfirmed(s, level, o);
      s.confirmed = why.empty();
      s.why_not_confirmed = why;
    }
    // No held-out share: no held-out logs, or rejected on the estimation data.
    const std::string held_out = std::isfinite(s.share_of_excess_held_out)
                                     ? NumberText(s.share_of_excess_held_out, "%.3f")
                                     : std::string("-");
    char line[512];
    std::snprintf(line, sizeof(line),
                  "  refit %-18s %5.1f s  Wald p = %-10.3g share of excess removed %.3f (held out "
                  "%s; all channels %.3f) %s%s",
                  s.effect.c_str(), refits[k].seconds, s.wald_p_value, s.share_of_excess,
                  held_out.c_str(), refits[k].share_of_all_excess,
                  s.confirmed ? "qualifies" : "rejected: ",
                  s.why_not_confirmed.c_str());
    Say(o, line);
    if (s.refit_starts.size() > 1) {
      std::string starts;
      for (const RefitStart& r : s.refit_starts) {
        starts += (starts.empty() ? "" : "; ") + r.from + ": cost " +
                  NumberText(r.cost, "%.6g") + " in " + NumberText(r.seconds, "%.1f s") +
                  (r.kept ? " (kept)" : "");
      }
      Say(o, "    " + std::to_string(s.refit_starts.size()) + " starts (the current fit's cost " +
                 NumberText(pass.fit.final_cost, "%.6g") + "; the lowest is kept): " + starts);
    }
  }
  return refits;
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
  if (!(min_share_of_excess >= 0 && min_share_of_excess < 1)) {
    *why = "min_share_of_excess must be in [0, 1)";
    return false;
  }
  if (!(min_channels_excess >= 0)) {
    *why = "min_channels_excess must be >= 0";
    return false;
  }
  if (fit_max_iterations < 1) {
    *why = "fit_max_iterations must be >= 1";
    return false;
  }
  if (max_refits < 1) {
    *why = "max_refits must be >= 1";
    return false;
  }
  if (!(decisive_share_of_all_excess > 0)) {
    *why = "decisive_share_of_all_excess must be > 0";
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

// Step 5 judged again once an effect is added: each added effect is taken
// out of the current model and the rest refitted warm from the current fit.
// An earlier-added effect that then removes less than min_share_of_excess of
// its channels' excess error (on the estimation or the held-out data) was
// standing in for the later one (a constant accelerometer bias for a
// height-dependent ground-effect thrust, one constant moment for another).
// The effect just added is judged the same way: its refit may have carried
// the declared parameters into a better basin (measured, ground-effect truth
// at 0.13-0.9 m, flight only, round 2: wind's refit from sigma0 restarted
// "removed" 48 % of the excess with Wald p = 6e-5; without wind, warm from
// that refit, the declared model keeps the gain), and then it is credited
// with the basin, not the effect. The least useful such effect leaves the
// model: *pass and *now become the fit without it. False if none is
// redundant.
bool DropRedundantEffect(const std::vector<EstimationLog>& estimation,
                         const std::vector<EstimationLog>& validation, const DiscoveryOptions& o,
                         int round, CandidatePass* pass, ModelSnapshot* now,
                         DiscoveryResult* out) {
  const std::string& latest = out->added.back();
  int worst = -1;
  RemovedEffect worst_removed;
  CandidatePass worst_pass;
  ModelSnapshot worst_snapshot;
  for (size_t i = 0; i < out->added.size(); ++i) {
    const std::string& effect = out->added[i];
    const bool itself = i + 1 == out->added.size();
    const auto t0 = Clock::now();
    const Vehicle without = WithoutEffect(pass->fitted, effect);
    const OutputErrorResult fit = WarmRefit(without, estimation, o.fit, pass->fitted, pass->fit);
    if (!fit.usable) continue;  // keep it: nothing to judge against
    Vehicle refitted = without;
    refitted.parameters = fit.parameters;
    ModelSnapshot snapshot = Snapshot(refitted, fit, estimation, validation, o);
    const std::vector<std::string> channels = ChannelsReachedBy(
        pass->fitted, EffectParameterNames(effect), estimation, pass->fit.noise);
    RemovedEffect r;
    r.effect = effect;
    r.made_redundant_by = itself ? std::string() : latest;
    r.round = round;
    r.share_of_excess =
        ShareOfExcessRemoved(snapshot.fit, now->fit, snapshot.residual_tests, channels).share;
    r.share_of_excess_held_out =
        validation.empty() ? NAN
                           : ShareOfExcessRemoved(snapshot.validation, now->validation,
                                                  snapshot.validation_residual_tests, channels)
                                 .share;
    Say(o, "  without " + effect + ", warm from the current fit (" +
               NumberText(SecondsSince(t0), "%.1f s") + "): it removes " +
               ShareText(r.share_of_excess, r.share_of_excess_held_out) +
               (itself ? std::string() : " in the model with " + latest));
    const bool material =
        r.share_of_excess >= o.min_share_of_excess &&
        !(std::isfinite(r.share_of_excess_held_out) &&
          r.share_of_excess_held_out < o.min_share_of_excess);
    if (material) continue;
    if (worst < 0 || r.share_of_excess < worst_removed.share_of_excess) {
      worst = static_cast<int>(i);
      worst_removed = r;
      worst_pass = LinearisePass(refitted, fit, estimation, o.fit);
      worst_snapshot = std::move(snapshot);
    }
  }
  if (worst < 0) return false;
  Say(o, "discover: removed " + worst_removed.effect +
             (worst_removed.made_redundant_by.empty()
                  ? ": its refit's gain came from the other parameters, not from it"
                  : ": made redundant by " + latest));
  out->added.erase(out->added.begin() + worst);
  out->removed.push_back(worst_removed);
  *pass = std::move(worst_pass);
  *now = std::move(worst_snapshot);
  return true;
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
  o.fit.max_iterations = std::min(o.fit.max_iterations, o.fit_max_iterations);
  o.fit.noise_relaxations = std::min(o.fit.noise_relaxations, 1);

  Vehicle start_vehicle = declared;
  OutputErrorOptions declared_fit = o.fit;
  out.start = "starting values from the config";
  if (options.ekf_start) {  // not usable without a flight log: the config start
    const EkfStart ekf = StartFromEkfPass(declared, estimation);
    Say(options, "discover: " + ekf.note);
    if (ekf.usable) {
      start_vehicle.parameters = ekf.parameters;
      declared_fit.segment_schedule_s = {o.fit.segment_schedule_s.back()};
      out.start = ekf.note;
    } else {
      out.start = ekf.note + "; starting values from the config";
    }
  }
  Say(options, "discover: fitting the declared model (" +
                   std::to_string(declared.parameters.FreeIndices().size()) + " free parameters)");
  OutputErrorResult fit = FitOutputError(start_vehicle, estimation, declared_fit);
  if (!fit.usable && fit.scale_move_failed) {
    // The declared model needs a scale member beyond its bounds (e.g. the
    // inertias of a vehicle with an undeclared constant moment): a symptom
    // (step 7). Fit with the scale held in the solve, so that member meets
    // its bound and the candidates' refits can move it back.
    Say(options, "discover: " + fit.why_not_usable +
                     "; refitting with the scale held in the solve (a symptom of a missing effect)");
    o.fit.scale_free_in_solve = false;
    declared_fit.scale_free_in_solve = false;
    fit = FitOutputError(start_vehicle, estimation, declared_fit);
  }
  if (!fit.usable) throw ComputationError("the declared model's fit failed: " + fit.why_not_usable);
  fit = Converged(declared, std::move(fit), estimation, o.fit, options);
  std::string restart_note;
  fit = RestartedOffBounds(declared, declared, std::move(fit), estimation, o.fit, options,
                           &restart_note);
  if (!restart_note.empty()) out.start += "; " + restart_note;
  Vehicle current = declared;
  current.parameters = fit.parameters;
  out.baseline = Snapshot(current, fit, estimation, validation, options);
  const std::vector<PlausibilityFinding> far =
      FarOutsidePhysicalRange(fit.parameters, declared.parameters);
  const std::vector<std::string> at_bounds = ParametersAtBounds(fit.parameters);
  for (const std::string& name : SymptomaticParameters(fit.parameters, declared.parameters)) {
    ParameterSymptom b;
    const Parameter& p = fit.parameters.Get(name);
    b.parameter = name;
    b.value = p.value;
    b.lower = p.lower;
    b.upper = p.upper;
    b.at_bound = std::find(at_bounds.begin(), at_bounds.end(), name) != at_bounds.end();
    for (const PlausibilityFinding& f : far) {
      if (f.subject != name) continue;
      b.physical_lower = f.lower;
      b.physical_upper = f.upper;
      b.why_outside = f.text;
    }
    b.channels = ChannelsReachedBy(current, {name}, estimation, fit.noise);
    out.symptoms.push_back(b);
  }

  CandidatePass pass = LinearisePass(current, fit, estimation, o.fit);
  ModelSnapshot now = out.baseline;
  Say(options, "discover: sensitivities of " + std::to_string(pass.candidates.size()) +
                   " candidate effects along the fit: " + NumberText(pass.seconds, "%.1f s"));
  for (int round = 1; round <= options.max_added + 1; ++round) {
    Say(options, "discover: round " + std::to_string(round) + ": scoring candidates against " +
                     (out.added.empty() ? std::string("the declared model")
                                        : "the model with " + std::to_string(out.added.size()) +
                                              " added effect(s)"));
    std::vector<CandidateScore> scores = ScoreCandidates(
        pass, estimation, options.alpha, round, WeightedExcess(now.residual_tests, pass.fit.noise));
    for (const CandidateScore& s : scores) {
      char line[256];
      std::snprintf(line, sizeof(line),
                    "  %-18s F = %-10.4g p = %-10.3g p_holm = %-10.3g predicted share %-8.3g %s",
                    s.effect.c_str(), s.statistic, s.p_value, s.p_corrected, s.predicted_share,
                    !s.testable ? "not testable" : s.passes ? "passes" : "fails");
      Say(options, line);
    }
    bool accepted = false;
    if (static_cast<int>(out.added.size()) < options.max_added) {
      std::vector<std::string> symptom_channels;
      std::map<std::string, std::vector<std::string>> distorted;
      for (const std::string& name : SymptomaticParameters(pass.fit.parameters, declared.parameters)) {
        distorted[name] = ChannelsReachedBy(pass.fitted, {name}, estimation, pass.fit.noise);
        for (const std::string& c : distorted[name]) symptom_channels.push_back(c);
      }
      MarkRestartsAtBounds(pass.fitted, declared, distorted, estimation, pass.fit.noise, &scores);
      std::vector<std::string> removed;  // a removed effect does not come back (no cycling)
      for (const RemovedEffect& r : out.removed) removed.push_back(r.effect);
      const std::vector<int> shortlist = Shortlist(scores, symptom_channels, removed,
                                                    options.max_refits, options.min_share_of_excess);
      for (int k : shortlist) {
        const CandidateScore& s = scores[k];
        if (s.restart_values.empty()) continue;
        std::string names;
        for (const auto& [name, value] : s.restart_values) names += (names.empty() ? "" : ", ") + name;
        Say(options, "  " + s.effect +
                         (s.blind_at_bounds ? " reaches the channels " + names +
                                                  " distort only off their bounds"
                                            : " acts on channels that " + names + " distort") +
                         ": its refit restarts them at the config values");
      }
      std::vector<CandidateRefit> refits = RefitInParallel(
          pass, estimation, validation, now, shortlist,
          ConfigValuesOfSymptomaticParameters(pass.fit.parameters, declared), &scores, o, start);
      std::vector<RefitOfRound> judged;
      for (size_t k = 0; k < refits.size(); ++k) {
        judged.push_back({&scores[shortlist[k]], refits[k].ok, refits[k].share_of_all_excess});
      }
      const RoundChoice choice =
          ChooseOfRound(judged, WaldLevel(options, shortlist.size()),
                        options.min_channels_excess, options.decisive_share_of_all_excess);
      const int best = choice.added;
      if (choice.vetoed >= 0) {
        CandidateScore& s = scores[shortlist[choice.vetoed]];
        const CandidateScore& d = scores[shortlist[choice.dominant]];
        s.confirmed = false;
        s.why_not_confirmed =
            "it removes " + NumberText(100 * refits[choice.vetoed].share_of_all_excess, "%.0f") +
            " % of the excess error over all channels, " + d.effect + " " +
            NumberText(100 * refits[choice.dominant].share_of_all_excess, "%.0f") +
            " % with a parameter at its bound (" + d.why_implausible +
            "): the missing physics is neither alone";
        Say(options, "discover: " + s.effect + " is not added: " + s.why_not_confirmed);
      }
      if (best >= 0) {
        const CandidateScore& s = scores[shortlist[best]];
        Say(options, "discover: added " + s.effect + " (Wald p = " +
                         NumberText(s.wald_p_value, "%.3g") + ", removes " +
                         NumberText(100 * s.share_of_excess, "%.0f") + " % of its channels' excess error)");
        pass = std::move(refits[best].next);
        now = std::move(refits[best].snapshot);
        if (pass.fit.hit_iteration_limit) {
          const OutputErrorResult fit = Converged(pass.fitted, pass.fit, estimation, o.fit, options);
          Vehicle v = pass.fitted;
          v.parameters = fit.parameters;
          pass = LinearisePass(v, fit, estimation, o.fit);
          now = Snapshot(v, fit, estimation, validation, options);
        }
        std::string restart_note;
        OutputErrorResult restarted = RestartedOffBounds(pass.fitted, declared, pass.fit, estimation,
                                                         o.fit, options, &restart_note);
        if (!restart_note.empty()) {
          Vehicle v = pass.fitted;
          v.parameters = restarted.parameters;
          pass = LinearisePass(v, restarted, estimation, o.fit);
          now = Snapshot(v, restarted, estimation, validation, options);
        }
        out.added.push_back(s.effect);
        accepted = true;
        DropRedundantEffect(estimation, validation, o, round, &pass, &now, &out);
      }
    }
    out.candidates.insert(out.candidates.end(), scores.begin(), scores.end());
    if (!accepted) break;
  }
  current = pass.fitted;
  out.final = std::move(now);
  const std::vector<std::string> still =
      SymptomaticParameters(out.final.result.parameters, declared.parameters);
  for (ParameterSymptom& b : out.symptoms) {
    b.released = std::find(still.begin(), still.end(), b.parameter) == still.end();
    std::string channels;
    for (const std::string& c : b.channels) channels += (channels.empty() ? "" : ", ") + c;
    const bool at_bound = b.at_bound;
    const std::string where =
        at_bound ? NumberText(b.value, "%.4g") +
                       (b.value - b.lower < b.upper - b.value ? ", its lower bound" : ", its upper bound")
                 : "a value far outside its physical range: " + b.why_outside;
    b.text = "the declared fit left " + b.parameter + " at " + where +
             ": a symptom of a missing effect; it distorts " + (channels.empty() ? "no channel" : channels) +
             (out.added.empty() ? std::string()
              : b.released      ? (at_bound ? "; the final model moved it back inside its bounds"
                                            : "; the final model moved it back towards its physical range")
                                : (at_bound ? "; it stays at the bound in the final model"
                                            : "; it stays far outside its range in the final model"));
    Say(options, "discover: " + b.text);
  }

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
  nlohmann::json symptoms = nlohmann::json::array();
  for (const ParameterSymptom& b : r.symptoms) {
    auto limit = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
    symptoms.push_back({{"parameter", b.parameter},
                        {"value", b.value},
                        {"bounds", {b.lower, b.upper}},
                        {"physical_range", b.why_outside.empty()
                                               ? nlohmann::json()
                                               : nlohmann::json::array({limit(b.physical_lower),
                                                                        limit(b.physical_upper)})},
                        {"channels", b.channels},
                        {"released_in_final_model", b.released},
                        {"text", b.text}});
  }
  nlohmann::json removed = nlohmann::json::array();
  for (const RemovedEffect& e : r.removed) {
    removed.push_back({{"effect", e.effect},
                       {"made_redundant_by", e.made_redundant_by.empty()
                                                 ? nlohmann::json()  // itself: its refit's basin
                                                 : nlohmann::json(e.made_redundant_by)},
                       {"round", e.round},
                       {"share_of_excess", e.share_of_excess},
                       {"share_of_excess_held_out", std::isfinite(e.share_of_excess_held_out)
                                                        ? nlohmann::json(e.share_of_excess_held_out)
                                                        : nlohmann::json()}});
  }
  return {{"baseline", SnapshotJson(r.baseline, has_validation)},
          {"start", r.start},
          {"symptoms", symptoms},
          {"candidates", candidates},
          {"added", r.added},
          {"removed", removed},
          {"added_parameters", added_parameters},
          {"final", SnapshotJson(r.final, has_validation)},
          {"unexplained", unexplained},
          {"settings",
           {{"alpha", options.alpha},
            {"correction", "Holm over the candidates tested in each round"},
            {"candidate_test",
             "score test of the nested model linearised at the current fit (candidate output "
             "sensitivities, estimated directions projected out), cluster-robust over "
             "multiple-shooting segments and balance holds (Hotelling T^2, F(q, M - q)); it "
             "shortlists: the passing candidates and those predicted to remove at least half "
             "of min_share_of_excess are refitted jointly (at most max_refits); a refit "
             "qualifies if its cluster-robust Wald p < alpha / refits, no parameter of it sits "
             "at a bound and it removes at least min_share_of_excess of its channels' excess "
             "error (an excess of at least min_channels_excess) on the estimation and the "
             "held-out data; the qualifying refit that removes the most excess error over all "
             "channels is added"},
            {"min_share_of_excess", options.min_share_of_excess},
            {"min_channels_excess", options.min_channels_excess},
            {"max_refits", options.max_refits},
            {"decisive_share_of_all_excess", options.decisive_share_of_all_excess},
            {"whiteness_test", "Ljung-Box, chi-square p-value by the regularized incomplete gamma"},
            {"ljung_box_lags", options.residuals.lags},
            {"unexplained_rms_ratio", options.unexplained_rms_ratio},
            {"prediction_window_s", options.window_s}}},
          {"seconds", r.seconds}};
}

}  // namespace coaxid
