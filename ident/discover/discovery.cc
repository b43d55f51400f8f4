#include "ident/discover/discovery.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <type_traits>

#include "core/errors.h"
#include "core/report.h"
#include "core/report_values.h"
#include "core/stopwatch.h"
#include "ident/discover/paired_refit.h"
#include "ident/discover/practical_significance.h"
#include "ident/discover/round_refits.h"
#include "ident/ekf/ekf_start.h"

namespace coaxid {
namespace {

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
//
// Restarted all together they may land in another wrong basin that one of
// them restarted alone avoids: unless the restart all together ends in the
// fit's basin (SameBasin), each is also restarted alone, side by side, and
// the lowest weighted RSS is kept
// (measured, seed 9909 of the confusion study, swashplate bias + wind, flight
// only: Cx, Cy, Cz and beta restarted together ended with beta back at its
// bound, the lower rotor's thrust gone, where no constant moment is testable;
// beta restarted alone within a candidate's refit removed 62 % of all the
// excess with the candidate's own parameters near absence; wind and
// gyroscopic were added. Each alone: beta's restart ended at 195082, kept;
// wind alone was added). A restart replaces the fit only when it gains at
// least restart_min_gain of the weighted RSS (DiscoveryOptions).
OutputErrorResult RestartedOffBounds(const Vehicle& model, const Vehicle& declared,
                                     OutputErrorResult fit, const std::vector<EstimationLog>& logs,
                                     const OutputErrorOptions& fit_options,
                                     const DiscoveryOptions& options, std::string* note) {
  const std::map<std::string, double> configs =
      ConfigValuesOfSymptomaticParameters(fit.parameters, declared);
  if (configs.empty()) return fit;
  auto names_of = [](const std::map<std::string, double>& r) {
    std::string names;
    for (const auto& [name, config] : r) names += (names.empty() ? "" : ", ") + name;
    return names;
  };
  Say(options, "discover: the fit left " + names_of(configs) +
                   " at a bound or far outside the physical range: refitting from their config "
                   "values" +
                   (configs.size() > 1 ? std::string(", all together first") : ""));
  int rows = 0;
  const double before = WeightedRss(logs, fit.predictions, fit.noise, &rows);
  std::vector<std::map<std::string, double>> restarts;
  std::vector<OutputErrorResult> refits;
  std::vector<double> rss;
  // Restarts side by side, each with its share of the threads, silent; the
  // weighted RSS of each, at the fit's noise weights.
  auto restart = [&](const std::vector<std::map<std::string, double>>& batch) {
    const int n = static_cast<int>(batch.size());
    OutputErrorOptions worker_options;
    const int workers = SideBySideWorkers(n, fit_options, &worker_options);
    std::vector<OutputErrorResult> done(n);
    SideBySide(n, workers, worker_options, [&](int k) {
      Vehicle restarted = model;
      restarted.parameters = fit.parameters;
      for (const auto& [name, config] : batch[k]) restarted.parameters.SetValue(name, config);
      done[k] = WarmRefit(restarted, logs, worker_options, model, fit, true);
    });
    for (int k = 0; k < n; ++k) {
      restarts.push_back(batch[k]);
      double after = INFINITY;
      if (!done[k].usable) {
        Say(options, "discover: the fit restarted with " + names_of(batch[k]) +
                         " at the config values failed: " + done[k].why_not_usable);
      } else {
        after = WeightedRss(logs, done[k].predictions, fit.noise, &rows);
        Say(options, "discover: the fit restarted with " + names_of(batch[k]) +
                         " at the config values: weighted RSS " + NumberText(after, "%.6g") +
                         " against " + NumberText(before, "%.6g"));
      }
      refits.push_back(std::move(done[k]));
      rss.push_back(after);
    }
  };
  restart({configs});
  if (configs.size() > 1) {
    if (!SameBasin(before, rss[0], options.restart_min_gain)) {
      std::vector<std::map<std::string, double>> singles;
      for (const auto& [name, config] : configs) singles.push_back({{name, config}});
      restart(singles);
    } else {
      Say(options, "discover: restarted all together they end within " +
                       NumberText(100 * options.restart_min_gain, "%.2g") +
                       " % of it, the same basin: not restarted each alone");
    }
  }
  const int best = RestartThatGains(before, rss, options.restart_min_gain);
  if (best < 0) {
    Say(options, "discover: no restart fits better by " +
                     NumberText(100 * options.restart_min_gain, "%.2g") + " %: the fit is kept");
    return fit;
  }
  *note = "the fit restarted with " + names_of(restarts[best]) +
          " at the config values: weighted RSS " + NumberText(rss[best], "%.6g") + " against " +
          NumberText(before, "%.6g") + ": kept";
  Say(options, "discover: " + *note);
  return Converged(model, std::move(refits[best]), logs, fit_options, options);
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
  if (!(min_share_to_reweight >= 0 && min_share_to_reweight < 1)) {
    *why = "min_share_to_reweight must be in [0, 1)";
    return false;
  }
  if (!(min_share_to_pair >= 0 && min_share_to_pair < 1)) {
    *why = "min_share_to_pair must be in [0, 1)";
    return false;
  }
  if (!(fit_rate_hz >= 0 && std::isfinite(fit_rate_hz))) {
    *why = "fit_rate_hz must be >= 0 (0: every log at its own rate)";
    return false;
  }
  if (!(search_window_s >= 0 && std::isfinite(search_window_s))) {
    *why = "search_window_s must be >= 0 (0: whole logs only)";
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
  if (!(restart_min_gain >= 0 && restart_min_gain < 1)) {
    *why = "restart_min_gain must be in [0, 1)";
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
// with the basin, not the effect. on_whole_logs: the effects the search
// window added, judged on the whole logs (no later addition to credit). The
// least useful such effect leaves the model: *pass and *now become the fit
// without it. False if none is redundant.
bool DropRedundantEffect(const std::vector<EstimationLog>& estimation,
                         const std::vector<EstimationLog>& validation, const DiscoveryOptions& o,
                         int round, bool on_whole_logs, CandidatePass* pass, ModelSnapshot* now,
                         DiscoveryResult* out) {
  const std::string& latest = out->added.back();
  int worst = -1;
  RemovedEffect worst_removed;
  CandidatePass worst_pass;
  ModelSnapshot worst_snapshot;
  for (size_t i = 0; i < out->added.size(); ++i) {
    const std::string& effect = out->added[i];
    const bool itself = i + 1 == out->added.size();
    const auto t0 = DiscoveryClock::now();
    const Vehicle without = WithoutEffect(pass->fitted, effect);
    const OutputErrorResult fit = WarmRefit(without, estimation, o.fit, pass->fitted, pass->fit);
    if (!fit.usable) continue;  // keep it: nothing to judge against
    Vehicle refitted = without;
    refitted.parameters = fit.parameters;
    ModelSnapshot snapshot = Snapshot(refitted, fit, estimation, {}, o);
    const std::string failed = TryAddValidation(validation, o, &snapshot);
    if (!failed.empty()) {
      Say(o, "  without " + effect + ": kept, the model without it fails on the held-out data (" +
                 failed + ")");
      continue;
    }
    const std::vector<std::string> channels = ChannelsReachedBy(
        pass->fitted, EffectParameterNames(effect), estimation, pass->fit.noise);
    RemovedEffect r;
    r.effect = effect;
    r.made_redundant_by = itself || on_whole_logs ? std::string() : latest;
    r.on_whole_logs = on_whole_logs;
    r.round = round;
    const ExcessShare estimation_share =
        ShareOfExcessRemoved(snapshot.fit, now->fit, snapshot.residual_tests, channels);
    r.share_of_excess = estimation_share.share;
    r.share_of_excess_held_out =
        validation.empty()
            ? NAN
            : HeldOutShareOfExcessRemoved(estimation_share, snapshot.validation, now->validation,
                                          snapshot.validation_residual_tests, channels);
    Say(o, "  without " + effect + ", warm from the current fit (" +
               NumberText(SecondsSince(t0), "%.1f s") + "): it removes " +
               ShareText(r.share_of_excess, r.share_of_excess_held_out) +
               (itself || on_whole_logs ? std::string() : " in the model with " + latest));
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
             (on_whole_logs ? ": the search window added it, the whole logs do not bear it out"
              : worst_removed.made_redundant_by.empty()
                  ? ": its refit's gain came from the other parameters, not from it"
                  : ": made redundant by " + latest));
  out->added.erase(out->added.begin() + worst);
  out->removed.push_back(worst_removed);
  *pass = std::move(worst_pass);
  *now = std::move(worst_snapshot);
  return true;
}

nlohmann::json SecondsByStepJson(const std::vector<std::pair<std::string, double>>& steps) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& [step, seconds] : steps) j.push_back({{"step", step}, {"seconds", seconds}});
  return j;
}

void AddStepSeconds(const std::string& step, double seconds,
                    std::vector<std::pair<std::string, double>>* steps) {
  for (auto& [name, total] : *steps) {
    if (name == step) {
      total += seconds;
      return;
    }
  }
  steps->emplace_back(step, seconds);
}

int RestartThatGains(double before, const std::vector<double>& after, double min_gain) {
  if (after.empty()) return -1;
  const int best = static_cast<int>(std::min_element(after.begin(), after.end()) - after.begin());
  return after[best] <= before * (1 - min_gain) ? best : -1;
}

bool SameBasin(double before, double after, double min_gain) {
  return std::fabs(after - before) <= min_gain * before;
}

std::vector<std::string> ExcludedEffects(const std::vector<RemovedEffect>& removed,
                                         int last_change_round) {
  std::vector<std::string> excluded;
  for (const RemovedEffect& r : removed) {
    if (r.round >= last_change_round) excluded.push_back(r.effect);
  }
  return excluded;
}

namespace {

// The steps of the loop, as discovery.json's seconds_by_step names them.
constexpr const char* kEkfStart = "EKF start";
constexpr const char* kDeclaredFit = "declared fit";
constexpr const char* kWindowModelFit = "the search window's model fitted to the whole logs";
constexpr const char* kContinued = "fits continued past their iteration cap";
constexpr const char* kRestarts = "restarts off the bounds";
constexpr const char* kSnapshots = "fit and held-out errors, residual tests";
constexpr const char* kSensitivities = "candidate sensitivities";
constexpr const char* kScores = "candidate scores";
constexpr const char* kRefits = "candidate refits";
constexpr const char* kJudgedAgain = "added effects judged again";
constexpr const char* kUnexplained = "unexplained channels, generic dictionary";

// Runs step() and adds its wall time to `name` (DiscoveryResult::seconds_by_step).
template <class Step>
auto Timed(DiscoveryResult* out, const char* name, Step&& step) {
  const auto t0 = DiscoveryClock::now();
  if constexpr (std::is_void_v<decltype(step())>) {
    step();
    AddStepSeconds(name, SecondsSince(t0), &out->seconds_by_step);
  } else {
    auto result = step();
    AddStepSeconds(name, SecondsSince(t0), &out->seconds_by_step);
    return result;
  }
}

// What the loop carries from round to round: the current model, fitted, its
// candidates' sensitivities along that fit, and how well it fits.
struct LoopState {
  CandidatePass pass;
  ModelSnapshot now;
};

// The loop's options: `options` with its fits capped (fit_function_tolerance,
// fit_max_iterations, at most one noise relaxation).
DiscoveryOptions LoopOptions(const DiscoveryOptions& options) {
  DiscoveryOptions o = options;
  o.fit.function_tolerance = std::max(o.fit.function_tolerance, o.fit_function_tolerance);
  o.fit.max_iterations = std::min(o.fit.max_iterations, o.fit_max_iterations);
  o.fit.noise_relaxations = std::min(o.fit.noise_relaxations, 1);
  return o;
}

// The fit `model` ends with: continued past its iteration cap (Converged),
// then, if restart_off_bounds, restarted off the bounds it leaves
// (RestartedOffBounds), the restart's note appended to *start_note if one
// is kept.
OutputErrorResult Settled(const Vehicle& model, const Vehicle& declared, OutputErrorResult fit,
                          const std::vector<EstimationLog>& logs, const DiscoveryOptions& o,
                          const DiscoveryOptions& options, DiscoveryResult* out,
                          std::string* start_note, bool restart_off_bounds = true) {
  fit = Timed(out, kContinued,
              [&] { return Converged(model, std::move(fit), logs, o.fit, options); });
  if (!restart_off_bounds) return fit;
  std::string restart_note;
  fit = Timed(out, kRestarts, [&] {
    return RestartedOffBounds(model, declared, std::move(fit), logs, o.fit, options, &restart_note);
  });
  if (!restart_note.empty() && start_note != nullptr) *start_note += "; " + restart_note;
  return fit;
}

// Step 1: the declared model fitted to `logs`, from a short EKF pass (or
// the config's values), settled; out->start says how it was started.
// `warm` (nullptr: none) is a declared fit of part of these logs (the search
// window's, started as `warm_start` says): the fit then starts from its
// values at the final segment length (restarted off its bounds only if
// restart_warm_fit), and from the EKF pass only if that fails. Throws
// ComputationError if no fit is usable. May hold the scale in the solve
// (o->fit).
OutputErrorResult FitDeclared(const Vehicle& declared, const std::vector<EstimationLog>& logs,
                              const OutputErrorResult* warm, const std::string& warm_start,
                              bool restart_warm_fit, const DiscoveryOptions& options,
                              DiscoveryOptions* o, DiscoveryResult* out) {
  Vehicle start_vehicle = declared;
  OutputErrorOptions declared_fit = o->fit;
  Say(options, "discover: fitting the declared model (" +
                   std::to_string(declared.parameters.FreeIndices().size()) + " free parameters)" +
                   (warm != nullptr ? " from its fit on the search window" : ""));
  auto fit_declared = [&] {
    return Timed(out, kDeclaredFit,
                 [&] { return FitOutputError(start_vehicle, logs, declared_fit); });
  };
  OutputErrorResult fit;
  if (warm != nullptr) {
    start_vehicle.parameters = warm->parameters;
    declared_fit.segment_schedule_s = {o->fit.segment_schedule_s.back()};
    if (warm->scale_held_in_solve) declared_fit.scale_free_in_solve = false;
    out->start = "from the declared fit on the search window (" + warm_start + ")";
    fit = fit_declared();
    if (fit.usable) {
      return Settled(declared, declared, std::move(fit), logs, *o, options, out, &out->start,
                     restart_warm_fit);
    }
    Say(options, "discover: the fit from the search window's failed (" + fit.why_not_usable +
                     "); fitting from the start the loop takes without a window");
    start_vehicle = declared;
    declared_fit = o->fit;
  }
  out->start = "starting values from the config";
  bool from_ekf = false;
  if (options.ekf_start) {  // not usable without a flight log: the config start
    const EkfStart ekf = Timed(out, kEkfStart, [&] { return StartFromEkfPass(declared, logs); });
    Say(options, "discover: " + ekf.note);
    if (ekf.usable) {
      start_vehicle.parameters = ekf.parameters;
      from_ekf = true;
      declared_fit.segment_schedule_s = {o->fit.segment_schedule_s.back()};
      out->start = ekf.note;
    } else {
      out->start = ekf.note + "; starting values from the config";
    }
  }
  fit = fit_declared();
  if (!fit.usable && !fit.scale_move_failed && from_ekf) {
    // The EKF's values can start the fit where the model cannot be integrated
    // (measured: seed 11183 of the controllers' study, a swashplate bias,
    // flight with the balance log: the first evaluation failed). The
    // config's values and the coarse-to-fine schedule are the start without it.
    Say(options, "discover: the fit from the EKF start failed (" + fit.why_not_usable +
                     "); fitting from the config's values");
    out->start += "; its fit failed: starting values from the config";
    start_vehicle = declared;
    declared_fit.segment_schedule_s = o->fit.segment_schedule_s;
    fit = fit_declared();
  }
  if (!fit.usable && fit.scale_move_failed) {
    // The declared model needs a scale member beyond its bounds (e.g. the
    // inertias of a vehicle with an undeclared constant moment): a symptom
    // (step 7). Fit with the scale held in the solve, so that member meets
    // its bound and the candidates' refits can move it back.
    Say(options, "discover: " + fit.why_not_usable +
                     "; refitting with the scale held in the solve (a symptom of a missing effect)");
    o->fit.scale_free_in_solve = false;
    declared_fit.scale_free_in_solve = false;
    fit = fit_declared();
  }
  if (!fit.usable) throw ComputationError("the declared model's fit failed: " + fit.why_not_usable);
  return Settled(declared, declared, std::move(fit), logs, *o, options, out, &out->start);
}

// The declared fit as the baseline (out->baseline) and its symptoms (step
// 7: parameters at a bound or far outside their range).
void SetBaseline(const Vehicle& declared, const OutputErrorResult& fit,
                 const std::vector<EstimationLog>& estimation,
                 const std::vector<EstimationLog>& validation, const DiscoveryOptions& options,
                 DiscoveryResult* out) {
  Vehicle current = declared;
  current.parameters = fit.parameters;
  out->baseline = Timed(out, kSnapshots,
                        [&] { return Snapshot(current, fit, estimation, validation, options); });
  const std::vector<PlausibilityFinding> far =
      FarOutsidePhysicalRange(fit.parameters, declared.parameters);
  const std::vector<std::string> at_bounds = ParametersAtBounds(fit.parameters);
  out->symptoms.clear();
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
    out->symptoms.push_back(b);
  }
}

// The loop's state at the baseline.
LoopState AtBaseline(const std::vector<EstimationLog>& estimation, const DiscoveryOptions& o,
                     const DiscoveryOptions& options, DiscoveryResult* out) {
  LoopState s;
  s.now = out->baseline;
  s.pass = Timed(out, kSensitivities,
                 [&] { return LinearisePass(s.now.vehicle, s.now.result, estimation, o.fit); });
  Say(options, "discover: sensitivities of " + std::to_string(s.pass.candidates.size()) +
                   " candidate effects along the fit: " + NumberText(s.pass.seconds, "%.1f s"));
  return s;
}

// Steps 2-6, round after round from `first_round` until a round adds
// nothing (or max_added are added): score the candidates against the
// current model, refit the shortlisted ones, add the best that qualifies,
// judge the added effects again. Returns the last round.
int Rounds(const Vehicle& declared, int first_round, int last_change_round,
           const std::vector<EstimationLog>& estimation,
           const std::vector<EstimationLog>& validation, const DiscoveryOptions& o,
           const DiscoveryOptions& options, DiscoveryClock::time_point start, LoopState* state,
           DiscoveryResult* out) {
  CandidatePass& pass = state->pass;
  ModelSnapshot& now = state->now;
  int round = first_round;
  for (;; ++round) {
    Say(options, "discover: round " + std::to_string(round) + ": scoring candidates against " +
                     (out->added.empty() ? std::string("the declared model")
                                         : "the model with " + std::to_string(out->added.size()) +
                                               " added effect(s)"));
    std::vector<CandidateScore> scores =
        Timed(out, kScores, [&] { return ScoreRound(pass, now, estimation, o, round); });
    std::vector<CandidateScore> beside;  // a paired refit's, reported after the round's
    bool accepted = false;
    if (static_cast<int>(out->added.size()) < options.max_added) {
      const std::vector<std::string> removed = ExcludedEffects(out->removed, last_change_round);
      RoundRefits refits = Timed(out, kRefits, [&] {
        return RefitShortlisted(pass, now, declared, removed, estimation, validation, &scores, o,
                                start);
      });
      // The model with a refit: continued if it stopped at its cap, and
      // restarted off the bounds it leaves.
      auto adopt = [&](CandidateRefit&& refit) {
        pass = std::move(refit.next);
        now = std::move(refit.snapshot);
        const bool capped = pass.fit.hit_iteration_limit;
        std::string restart_note;  // not empty: a restart was kept
        const OutputErrorResult fit = Settled(pass.fitted, declared, pass.fit, estimation, o,
                                              options, out, &restart_note);
        if (!capped && restart_note.empty()) return;  // the refit's own fit, as it was
        Vehicle v = pass.fitted;
        v.parameters = fit.parameters;
        pass = Timed(out, kSensitivities, [&] { return LinearisePass(v, fit, estimation, o.fit); });
        now = Timed(out, kSnapshots,
                    [&] { return Snapshot(v, fit, estimation, validation, options); });
      };
      const int best = refits.choice.added;
      if (best >= 0) {
        const CandidateScore& s = scores[refits.shortlist[best]];
        Say(options, "discover: added " + s.effect +
                         " (Wald p = " + NumberText(s.wald_p_value, "%.3g") + ", removes " +
                         NumberText(100 * s.share_of_excess, "%.0f") +
                         " % of its channels' excess error)");
        adopt(std::move(refits.refits[best]));
        out->added.push_back(s.effect);
        accepted = true;
      } else if (static_cast<int>(out->added.size()) + 2 <= options.max_added) {
        PairedRefit pair = Timed(out, kRefits, [&] {
          return RefitBesideABound(pass, now, refits, &scores, declared, removed, estimation,
                                   validation, o, round, start);
        });
        beside = std::move(pair.beside);
        if (pair.added || pair.second_alone) {
          adopt(std::move(pair.joint));
          if (pair.added) out->added.push_back(pair.first);
          out->added.push_back(pair.second);
          accepted = true;
        }
      }
      if (accepted) {
        // Taking one effect out changes what the others remove: they are
        // judged again, in the model without it, until none is redundant
        // (measured, seed 10268 of the confusion study, swashplate bias with
        // the balance log: wind and cg_offset added as a pair in round 1;
        // with swashplate_bias added in round 2, without wind the rest lost
        // 0.2 % of wind's channels' excess and without cg_offset 0.0 %;
        // cg_offset was taken out and wind, judged once, stayed).
        const std::string latest = out->added.back();
        Timed(out, kJudgedAgain, [&] {
          while (DropRedundantEffect(estimation, validation, o, round, false, &pass, &now, out) &&
                 std::find(out->added.begin(), out->added.end(), latest) != out->added.end()) {
          }
        });
        if (std::find(out->added.begin(), out->added.end(), latest) != out->added.end()) {
          last_change_round = round;
        }
      }
    }
    out->candidates.insert(out->candidates.end(), scores.begin(), scores.end());
    out->candidates.insert(out->candidates.end(), beside.begin(), beside.end());
    if (!accepted) return round;
  }
}

// The estimation logs as the search window takes them: each flight log
// longer than twice search_window_s cut to its first search_window_s, the
// others whole. Empty if no log is cut (the loop then searches the whole
// logs).
std::vector<EstimationLog> SearchWindowLogs(const std::vector<EstimationLog>& estimation,
                                            double search_window_s, std::vector<std::string>* cut) {
  if (!(search_window_s > 0)) return {};
  std::vector<EstimationLog> window;
  for (const EstimationLog& log : estimation) {
    const std::vector<double>& t = log.inputs.times();
    if (log.kind == LogKind::kFlight && t.back() - t.front() > 2 * search_window_s) {
      window.push_back(FirstSecondsOf(log, search_window_s));
      cut->push_back(log.source);
    } else {
      window.push_back(log);
    }
  }
  if (cut->empty()) return {};
  return window;
}

// The search on the window (`window`, the held-out logs whole): the declared
// fit and every round, into *w. False (and *why) if it failed: a fit of the
// window may be a model that cannot be simulated on the held-out logs.
bool SearchWindow(const Vehicle& declared, const std::vector<EstimationLog>& window,
                  const std::vector<EstimationLog>& validation, const DiscoveryOptions& options,
                  DiscoveryOptions* o, DiscoveryClock::time_point start, DiscoveryResult* w,
                  OutputErrorResult* declared_fit, int* rounds, std::string* why) {
  try {
    *declared_fit = FitDeclared(declared, window, nullptr, "", true, options, o, w);
    SetBaseline(declared, *declared_fit, window, validation, options, w);
    LoopState state = AtBaseline(window, *o, options, w);
    *rounds = Rounds(declared, 1, 0, window, validation, *o, options, start, &state, w);
    w->final = std::move(state.now);
    return true;
  } catch (const ComputationError& e) {
    *why = e.what();
    return false;
  }
}

// The model the search window ended with, fitted to the whole logs from its
// values at the final segment length and settled; its effects judged again
// there (DropRedundantEffect: one that removes too little of its channels'
// excess on the whole logs leaves the model, `round` its removal's round).
// False if that model's fit fails, or the fit cannot be simulated on the
// held-out logs.
bool ConfirmOnWholeLogs(const Vehicle& declared, const ModelSnapshot& window_final,
                        const std::vector<EstimationLog>& estimation,
                        const std::vector<EstimationLog>& validation, int round,
                        const DiscoveryOptions& o, const DiscoveryOptions& options,
                        LoopState* state, DiscoveryResult* out) {
  const Vehicle& model = window_final.vehicle;
  OutputErrorOptions fit_options = o.fit;
  fit_options.segment_schedule_s = {o.fit.segment_schedule_s.back()};
  if (window_final.result.scale_held_in_solve) fit_options.scale_free_in_solve = false;
  Say(options, "discover: the search window's model (with " + Joined(out->added, ", ") +
                   ") fitted to the whole logs");
  OutputErrorResult fit =
      Timed(out, kWindowModelFit, [&] { return FitOutputError(model, estimation, fit_options); });
  if (!fit.usable) {
    Say(options, "discover: that fit failed: " + fit.why_not_usable);
    return false;
  }
  fit = Settled(model, declared, std::move(fit), estimation, o, options, out, nullptr);
  Vehicle v = model;
  v.parameters = fit.parameters;
  state->pass =
      Timed(out, kSensitivities, [&] { return LinearisePass(v, fit, estimation, o.fit); });
  const std::string failed = Timed(out, kSnapshots, [&] {
    state->now = Snapshot(v, fit, estimation, {}, options);
    return TryAddValidation(validation, options, &state->now);
  });
  if (!failed.empty()) {
    Say(options, "discover: that model fails on the held-out data: " + failed);
    return false;
  }
  Timed(out, kJudgedAgain, [&] {
    while (!out->added.empty() && DropRedundantEffect(estimation, validation, o, round, true,
                                                      &state->pass, &state->now, out)) {
    }
  });
  return true;
}

// Steps 7 and the report's end: the final model, what became of the
// declared fit's symptoms, and the channels left unexplained.
void Conclude(const Vehicle& declared, const std::vector<EstimationLog>& estimation,
              const DiscoveryOptions& options, LoopState* state, DiscoveryResult* out) {
  out->final = std::move(state->now);
  const std::vector<std::string> still =
      SymptomaticParameters(out->final.result.parameters, declared.parameters);
  for (ParameterSymptom& b : out->symptoms) {
    b.released = std::find(still.begin(), still.end(), b.parameter) == still.end();
    std::string channels;
    for (const std::string& c : b.channels) channels += (channels.empty() ? "" : ", ") + c;
    const bool at_bound = b.at_bound;
    const std::string where =
        at_bound ? NumberText(b.value, "%.4g") +
                       (b.value - b.lower < b.upper - b.value ? ", its lower bound" : ", its upper bound")
                 : "a value far outside its physical range: " + b.why_outside;
    b.text =
        "the declared fit left " + b.parameter + " at " + where +
        ": a symptom of a missing effect; it distorts " +
        (channels.empty() ? "no channel" : channels) +
        (out->added.empty() ? std::string()
         : b.released       ? (at_bound ? "; the final model moved it back inside its bounds"
                                        : "; the final model moved it back towards its physical range")
                            : (at_bound ? "; it stays at the bound in the final model"
                                        : "; it stays far outside its range in the final model"));
    Say(options, "discover: " + b.text);
  }

  for (const ChannelResidualTest& t : out->final.residual_tests) {
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
    u.generic = Timed(out, kUnexplained, [&] {
      return SearchChannelDictionary(estimation, out->final.result.predictions, t.channel,
                                     options.dictionary);
    });
    out->unexplained.push_back(u);
  }
}

}  // namespace

DiscoveryResult Discover(const Vehicle& declared, const std::vector<EstimationLog>& logs,
                         const std::vector<EstimationLog>& held_out,
                         const DiscoveryOptions& options) {
  const auto start = DiscoveryClock::now();
  std::string why;
  if (!options.IsValid(&why)) throw InputError("discover options: " + why);
  if (logs.empty()) throw InputError("discover: no estimation log");
  DiscoveryResult out;
  out.estimation = AtFitRate(logs, options.fit_rate_hz);
  out.validation = AtFitRate(held_out, options.fit_rate_hz);
  std::vector<EstimationLog> estimation, validation;  // what every step below fits and judges
  for (const LogAtFitRate& a : out.estimation) {
    estimation.push_back(a.log);
    if (a.log.kind == LogKind::kFlight) Say(options, "discover: " + a.note);
  }
  for (const LogAtFitRate& a : out.validation) {
    validation.push_back(a.log);
    if (a.log.kind == LogKind::kFlight) Say(options, "discover: held out " + a.note);
  }
  DiscoveryOptions o = LoopOptions(options);

  // The search on a window of the long flight logs, confirmed on the whole
  // logs (DiscoveryOptions::search_window_s).
  LoopState state;
  bool have_baseline = false;
  int first_round = 1, last_change_round = 0;
  std::vector<std::string> cut;
  const std::vector<EstimationLog> window =
      SearchWindowLogs(estimation, options.search_window_s, &cut);
  if (!window.empty()) {
    out.search_window.logs = cut;
    out.search_window.seconds = options.search_window_s;
    Say(options, "discover: searching the first " + NumberText(options.search_window_s, "%g s") +
                     " of " + Joined(cut, ", ") + ", then confirming on the whole logs");
    DiscoveryResult w;
    DiscoveryOptions window_o = o;
    OutputErrorResult window_declared;
    int rounds = 0;
    std::string failed;
    const bool searched = SearchWindow(declared, window, validation, options, &window_o, start, &w,
                                       &window_declared, &rounds, &failed);
    for (const auto& [step, seconds] : w.seconds_by_step) {
      AddStepSeconds(step, seconds, &out.seconds_by_step);
    }
    if (!searched) {
      out.search_window.note = "the search on the window failed (" + failed + ")";
      Say(options, "discover: " + out.search_window.note + ": searching the whole logs");
    } else {
      Say(options, "discover: the search on the window ended after round " +
                       std::to_string(rounds) + " (" + NumberText(SecondsSince(start), "%.1f s") +
                       " so far), having added " +
                       (w.added.empty() ? std::string("nothing") : Joined(w.added, ", ")) +
                       ": the whole logs now");
      o = window_o;  // with the scale held in the solve if the window's fit needed it
      out.search_window.rounds = rounds;
      out.search_window.added = w.added;
      out.search_window.start = w.start;
      // Where the window added effects, the rounds go on from its model and
      // the declared fit is the report's baseline alone: it starts in the
      // basin the window's declared fit chose, and is not restarted off its
      // bounds again (measured, 22469 of the confusion spec: restarting it
      // took five fits of the 60 s log and 5.4 s of the run's 28.2 s, for 2.4 %
      // of the baseline's weighted RSS).
      const OutputErrorResult declared_fit = FitDeclared(
          declared, estimation, &window_declared, w.start, w.added.empty(), options, &o, &out);
      SetBaseline(declared, declared_fit, estimation, validation, options, &out);
      have_baseline = true;
      out.added = w.added;
      out.candidates = std::move(w.candidates);
      out.removed = std::move(w.removed);
      bool confirmed = true;
      if (w.added.empty()) {
        state = AtBaseline(estimation, o, options, &out);
      } else if (!ConfirmOnWholeLogs(declared, w.final, estimation, validation, rounds + 1, o,
                                     options, &state, &out)) {
        // The whole search from the start, its declared fit restarted off
        // its bounds as the rounds need it.
        confirmed = false;
        have_baseline = false;
        out.search_window.note =
            "the window's model could not be fitted to the whole logs or simulated on the "
            "held-out logs";
        Say(options, "discover: " + out.search_window.note + ": searching the whole logs");
        out.added.clear();
        out.candidates.clear();
        out.removed.clear();
      }
      out.search_window.used = confirmed;
      if (confirmed) first_round = last_change_round = rounds + 1;
    }
  }
  if (!have_baseline) {  // no window, or its search failed
    const OutputErrorResult fit =
        FitDeclared(declared, estimation, nullptr, "", true, options, &o, &out);
    SetBaseline(declared, fit, estimation, validation, options, &out);
    state = AtBaseline(estimation, o, options, &out);
  }
  Rounds(declared, first_round, last_change_round, estimation, validation, o, options, start,
         &state, &out);
  Conclude(declared, estimation, options, &state, &out);
  out.seconds = SecondsSince(start);
  std::vector<std::string> steps;  // those that round to 0.1 s or more
  for (const auto& [step, seconds] : out.seconds_by_step) {
    if (seconds >= 0.05) steps.push_back(step + " " + NumberText(seconds, "%.1f s"));
  }
  if (!steps.empty()) Say(options, "discover: time by step: " + Joined(steps, ", "));
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
                       {"on_whole_logs", e.on_whole_logs},
                       {"round", e.round},
                       {"share_of_excess", e.share_of_excess},
                       {"share_of_excess_held_out", std::isfinite(e.share_of_excess_held_out)
                                                        ? nlohmann::json(e.share_of_excess_held_out)
                                                        : nlohmann::json()}});
  }
  nlohmann::json fitted_logs = nlohmann::json::array();
  for (const std::vector<LogAtFitRate>* set : {&r.estimation, &r.validation}) {
    for (const LogAtFitRate& a : *set) {
      fitted_logs.push_back({{"log", a.log.source},
                             {"held_out", set == &r.validation},
                             {"rate_hz", a.log_rate_hz},
                             {"rows_averaged", a.rows_averaged},
                             {"note", a.note}});
    }
  }
  const DiscoveryResult::SearchWindow& w = r.search_window;
  const nlohmann::json search_window =
      w.logs.empty()
          ? nlohmann::json()
          : nlohmann::json{{"seconds", w.seconds}, {"logs", w.logs},   {"used", w.used},
                           {"rounds", w.rounds},   {"added", w.added}, {"start", w.start},
                           {"note", w.note}};
  return {{"fitted_logs", fitted_logs},
          {"search_window", search_window},
          {"baseline", SnapshotJson(r.baseline, has_validation)},
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
             "of min_share_of_excess are refitted jointly (at most max_refits), and the one "
             "with the smallest p-value if below alpha before Holm and not yet listed; where "
             "the fit holds parameters at a bound, at most max_refits more acting on the "
             "channels they distort, restarted off them (passing ones the first slots left out "
             "before those failing the score test, both counted only if none of the first "
             "slots' is added), and, only if none of those is added, "
             "every other one acting on a channel the fit has lost; one whose channels hold "
             "less than min_channels_excess of excess error in the current fit is not "
             "refitted (no refit of it could qualify); a refit "
             "qualifies if its cluster-robust Wald p < alpha / refits, no parameter of it sits "
             "at a bound and it removes at least min_share_of_excess of its channels' excess "
             "error (an excess of at least min_channels_excess) on the estimation and the "
             "held-out data (the held-out data judge it when at least half of its gain on the "
             "estimation data lies in channels they measure); the qualifying refit that removes "
             "the most excess error over all channels is added, unless a refit removes "
             "materially more of it (at least min_share_of_excess of what the qualifying one "
             "leaves): significantly, with a parameter of its own at a bound, and at least "
             "decisive_share_of_all_excess of it; "
             "or not significantly, and at least min_share_of_excess of it; a round that adds "
             "nothing but holds a significant refit that "
             "removes at least min_share_to_pair of its channels' excess error with a parameter "
             "of its own at a bound, or the refit that held its qualifying one back, is "
             "refitted with that candidate in the "
             "model, and the best candidate qualifying there is added with it if, at their "
             "joint refit, it is inside its bounds and significant and the pair removes at "
             "least min_share_of_excess of their channels' excess error (if beside it the first "
             "stays at its bound or is not significant, a second the round held back is added "
             "alone from its own refit); after each addition every added effect is judged again "
             "and one that no longer removes min_share_of_excess is removed (the least useful "
             "first, the others judged again without it), a candidate again once a later "
             "addition stays in the model; a fit that leaves parameters at a bound is refitted "
             "with them restarted at their config values, all together and, unless that ends "
             "within restart_min_gain of the fit's weighted RSS, each alone; the lowest "
             "weighted RSS is kept if it gains that much"},
            {"fit_rate_hz", options.fit_rate_hz},
            {"min_share_of_excess", options.min_share_of_excess},
            {"min_channels_excess", options.min_channels_excess},
            {"min_share_to_reweight", options.min_share_to_reweight},
            {"min_share_to_pair", std::min(options.min_share_to_pair, options.min_share_of_excess)},
            {"max_refits", options.max_refits},
            {"decisive_share_of_all_excess", options.decisive_share_of_all_excess},
            {"restart_min_gain", options.restart_min_gain},
            {"search_window_s", options.search_window_s},
            {"whiteness_test", "Ljung-Box, chi-square p-value by the regularized incomplete gamma"},
            {"ljung_box_lags", options.residuals.lags},
            {"unexplained_rms_ratio", options.unexplained_rms_ratio},
            {"prediction_window_s", options.window_s}}},
          {"seconds", r.seconds},
          {"seconds_by_step", SecondsByStepJson(r.seconds_by_step)}};
}

}  // namespace coaxid
