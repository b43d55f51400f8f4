#include "ident/discover/round_refits.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <thread>

#include "core/errors.h"
#include "core/report_values.h"
#include "core/stopwatch.h"
#include "ident/discover/practical_significance.h"
#include "ident/discover/shortlist.h"

namespace coaxid {

void Say(const DiscoveryOptions& o, const std::string& line) {
  if (o.progress) o.progress(line);
}

int SideBySideWorkers(int n, const OutputErrorOptions& fit, OutputErrorOptions* worker) {
  const int workers = std::max(1, std::min(n, fit.num_threads));
  *worker = fit;
  worker->progress = nullptr;
  worker->num_threads = std::max(1, fit.num_threads / workers);
  // One worker is the calling thread: it keeps the pool it was lent from.
  if (workers > 1) worker->spare_threads = std::make_shared<SpareThreads>();
  return workers;
}

void SideBySide(int n, int workers, const OutputErrorOptions& worker_options,
                const std::function<void(int)>& task) {
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int k = next++; k < n; k = next++) task(k);
    // Out of tasks: its threads go to the fits still running (one worker
    // alone is the caller, which goes on).
    if (workers > 1 && worker_options.spare_threads)
      worker_options.spare_threads->Add(worker_options.num_threads);
  };
  std::vector<std::thread> threads;
  for (int w = 1; w < workers; ++w) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
}

void AddValidation(const std::vector<EstimationLog>& validation, const DiscoveryOptions& o,
                   ModelSnapshot* s) {
  if (validation.empty()) return;
  s->validation_predictions =
      PredictWithFixedParameters(s->vehicle, validation, s->result.noise, o.window_s, o.fit);
  s->validation = ChannelFitErrors(validation, s->validation_predictions);
  s->validation_residual_tests = AnalyseResiduals(validation, s->validation_predictions, o.residuals);
}

std::string TryAddValidation(const std::vector<EstimationLog>& validation,
                             const DiscoveryOptions& o, ModelSnapshot* s) {
  try {
    AddValidation(validation, o, s);
  } catch (const ComputationError& e) {
    return e.what();
  }
  return "";
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

double WaldLevel(const DiscoveryOptions& o, size_t refitted) {
  return o.alpha / static_cast<double>(std::max<size_t>(1, refitted));
}

namespace {

std::string WhyNoExcess(double channels_excess, const DiscoveryOptions& o) {
  return "its channels hold almost no excess error to remove (" +
         NumberText(channels_excess, "%.3g") + " noise variances, below " +
         NumberText(o.min_channels_excess, "%.3g") + ")";
}

}  // namespace

std::string WhyNotSignificant(const CandidateScore& s, double level, const DiscoveryOptions& o) {
  if (!(s.wald_p_value < level)) {
    return "its parameters are not significantly away from absence at the refit (cluster-robust "
           "Wald p = " + NumberText(s.wald_p_value, "%.3g") + ", level " +
           NumberText(level, "%.3g") + ")";
  }
  if (!s.plausible) return "not physically meaningful: " + s.why_implausible;
  if (!(s.channels_excess >= o.min_channels_excess)) return WhyNoExcess(s.channels_excess, o);
  return "";
}

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

namespace {

// "<effect>'s refit still predicts <channels> no better than their mean":
// why the refits waiting behind a qualifying one run (shortlist.h).
std::string StillLosesText(const std::string& effect, const std::vector<std::string>& still_lost) {
  return "  " + effect + "'s refit still predicts " + Joined(still_lost) +
         " no better than their mean";
}

std::vector<RefitOfRound> Judged(const std::vector<CandidateRefit>& refits,
                                 const std::vector<int>& shortlist,
                                 const std::vector<CandidateScore>& scores, size_t count);

// Refits the shortlisted candidates one at a time, in shortlist order, and
// judges each: Wald p below alpha over the `family` of refits (Bonferroni),
// no parameter at a bound, and at least min_share_of_excess of its channels'
// excess error removed on the estimation data and on the held-out data. The
// first that qualifies and removes at least decisive_share_of_all_excess of
// the excess over all channels decides: those ranked below it are not
// refitted. Those from `waits_from` on count only if the round adds none of
// those before them (ChooseOfRound), and are refitted only then, or when the
// one it adds still loses a channel of `lost_channels` they act on: its
// refit predicts it no better than the mean (LostChannels, shortlist.h).
std::vector<CandidateRefit> RefitInRankOrder(
    const CandidatePass& pass, const std::vector<EstimationLog>& estimation,
    const std::vector<EstimationLog>& validation, const ModelSnapshot& now,
    const std::vector<int>& shortlist, size_t family,
    const std::map<std::string, double>& declared_at_bounds, std::vector<CandidateScore>* scores,
    const DiscoveryOptions& o, DiscoveryClock::time_point start, size_t waits_from = SIZE_MAX,
    const std::vector<std::string>& lost_channels = {}) {
  const int n = static_cast<int>(shortlist.size());
  const int waiting = static_cast<int>(std::min<size_t>(waits_from, shortlist.size()));
  std::vector<CandidateRefit> refits(n);
  if (n == 0) return refits;
  std::string names;
  for (int k : shortlist) names += (names.empty() ? "" : ", ") + (*scores)[k].effect;
  Say(o, "discover: refitting " + names + " jointly (" +
             NumberText(SecondsSince(start), "%.1f s") + " so far)");
  // Each refit with every thread, silent (the loop reports each result). One
  // at a time rather than side by side: the first refit decides its round
  // often, and a refit alone on two threads takes about 0.55 of its time on
  // one (measured, bench/discover_speed.sh: in 33 of 70 rounds of more than
  // one refit on 80 logs the first decided; docs/discover_confusion.md, "One
  // refit at a time").
  DiscoveryOptions quiet = o;
  quiet.fit.progress = nullptr;
  const double level = WaldLevel(o, family);
  int decided_by = n;  // the decisive refit, if one is
  // Candidates whose channels hold less excess error than a refit must have
  // to remove (min_channels_excess) in the current fit: no refit of theirs
  // could be added (WhyNotSignificant), hold back another (ChooseOfRound) or
  // start a pair (FirstOfAPair), each of which asks for that excess, set by
  // the current fit alone; so none is run (measured: the last round of
  // confusion seed 22076, its two effects found and every channel at
  // 0.97-1.03 x its noise, refitted five candidates for 6.5 s).
  std::vector<char> without_excess(n, 0);
  auto evaluate = [&](int k) {
    CandidateScore& s = (*scores)[shortlist[k]];
    const double excess = ChannelsExcess(now.fit, now.residual_tests, s.channels);
    if (!(excess >= o.min_channels_excess) && !o.refit_without_excess) {
      s.channels_excess = excess;
      s.why_not_confirmed = "not refitted: " + WhyNoExcess(excess, o);
      without_excess[k] = 1;
      return;
    }
    OutputErrorResult refit;
    ReweightingGate reweighting;
    reweighting.min_share = std::min(o.min_share_to_reweight, o.min_share_of_excess);
    reweighting.share = [&](const OutputErrorResult& r) {
      return ShareOfExcessRemoved(now.fit, ChannelFitErrors(estimation, r.predictions),
                                  now.residual_tests, s.channels)
          .share;
    };
    const bool usable = RefitCandidate(pass, estimation, quiet.fit, declared_at_bounds, &s, &refit,
                                       &refits[k].next, reweighting);
    if (!usable) return;
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
      const std::string failed = TryAddValidation(validation, quiet, &refits[k].snapshot);
      if (!failed.empty()) {
        s.why_not_confirmed = "its model fails on the held-out data: " + failed;
        return;
      }
      s.share_of_excess_held_out =
          HeldOutShareOfExcessRemoved(est, now.validation, refits[k].snapshot.validation,
                                      now.validation_residual_tests, s.channels);
    }
    refits[k].ok = true;
    if (all.share >= o.decisive_share_of_all_excess && WhyNotConfirmed(s, level, o).empty()) {
      decided_by = k;
    }
  };
  // Refits first ... last - 1, up to a decisive one.
  auto refit_range = [&](int first, int last) {
    for (int k = first; k < last && decided_by == n; ++k) {
      const auto t0 = DiscoveryClock::now();
      evaluate(k);
      refits[k].seconds = SecondsSince(t0);
    }
  };
  refit_range(0, waiting);
  // Refit k's score marked not refitted, with why.
  auto set_back = [&](int k, const std::string& why) {
    CandidateScore& s = (*scores)[shortlist[k]];
    s.refitted = false;
    s.refit_starts.clear();
    s.confirmed = false;
    s.why_not_confirmed = why;
  };
  // The waiting ones: set aside if the round adds one of those before them,
  // refitted otherwise.
  const size_t judged_before = static_cast<size_t>(std::min(waiting, decided_by + 1));
  for (size_t k = 0; k < judged_before; ++k) {
    CandidateScore& s = (*scores)[shortlist[k]];
    if (refits[k].ok) s.confirmed = WhyNotConfirmed(s, level, o).empty();
  }
  const RoundChoice before =
      ChooseOfRound(Judged(refits, shortlist, *scores, judged_before), level,
                    o.min_channels_excess, o.decisive_share_of_all_excess, o.min_share_of_excess);
  std::vector<char> set_aside(n, 0);
  std::string refitted_on_still_lost;  // why waiting ones were refitted though one qualified
  if (before.added >= 0) {
    const CandidateScore& added = (*scores)[shortlist[before.added]];
    const ModelSnapshot& with_it = refits[before.added].snapshot;
    const std::vector<std::string> still_lost =
        decided_by == n ? LostChannels(with_it.fit, with_it.residual_tests, lost_channels)
                        : std::vector<std::string>();
    for (int k = waiting; k < n; ++k) {
      if (ReachesAny((*scores)[shortlist[k]].channels, still_lost)) {
        refit_range(k, k + 1);
        refitted_on_still_lost = StillLosesText(added.effect, still_lost) +
                                 ": those acting there were refitted beside it";
        continue;
      }
      set_back(k, "not refitted: " + added.effect +
                  ", refitted before it, qualifies; the next round tests it against the "
                  "model with " + added.effect);
      set_aside[k] = 1;
    }
  } else {
    refit_range(waiting, n);
  }
  for (int k = 0; k < n; ++k) {
    CandidateScore& s = (*scores)[shortlist[k]];
    if (set_aside[k] || without_excess[k]) {
      Say(o, "  refit " + s.effect + ": " + s.why_not_confirmed);
      continue;
    }
    const int decider = decided_by;
    if (k > decider) {
      const std::string& effect = (*scores)[shortlist[decider]].effect;
      set_back(k, "not judged: " + effect + ", ranked above it, qualifies and removes " +
                  NumberText(100 * refits[decider].share_of_all_excess, "%.0f") +
                  " % of the excess error over all channels; the next round tests it "
                  "against the model with " + effect);
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
  if (!refitted_on_still_lost.empty()) Say(o, refitted_on_still_lost);
  return refits;
}


// The first `count` of a round's refits as ChooseOfRound reads them.
std::vector<RefitOfRound> Judged(const std::vector<CandidateRefit>& refits,
                                 const std::vector<int>& shortlist,
                                 const std::vector<CandidateScore>& scores, size_t count) {
  std::vector<RefitOfRound> judged;
  for (size_t k = 0; k < std::min(count, refits.size()); ++k) {
    judged.push_back({&scores[shortlist[k]], refits[k].ok, refits[k].share_of_all_excess});
  }
  return judged;
}

std::vector<RefitOfRound> Judged(const RoundRefits& r, const std::vector<CandidateScore>& scores) {
  return Judged(r.refits, r.shortlist, scores, r.refits.size());
}

// What the round adds of r's refits, at the Wald level of `family`; a
// qualifying refit vetoed by a dominant one (at a bound, or not significant)
// is marked so and reported.
void ChooseAndSay(RoundRefits* r, size_t family, std::vector<CandidateScore>* scores,
                  const DiscoveryOptions& o) {
  const double level = WaldLevel(o, family);
  r->choice = ChooseOfRound(Judged(*r, *scores), level, o.min_channels_excess,
                            o.decisive_share_of_all_excess, o.min_share_of_excess);
  if (r->choice.vetoed >= 0) {
    CandidateScore& s = (*scores)[r->shortlist[r->choice.vetoed]];
    const CandidateScore& d = (*scores)[r->shortlist[r->choice.dominant]];
    s.confirmed = false;
    const std::string how =
        d.wald_p_value < level
            ? "with a parameter at its bound (" + d.why_implausible + ")"
            : "though not significant (cluster-robust Wald p = " +
                  NumberText(d.wald_p_value, "%.3g") + ", level " + NumberText(level, "%.3g") + ")";
    s.why_not_confirmed =
        "it removes " + NumberText(100 * r->refits[r->choice.vetoed].share_of_all_excess, "%.0f") +
        " % of the excess error over all channels, " + d.effect + " " +
        NumberText(100 * r->refits[r->choice.dominant].share_of_all_excess, "%.0f") + " % " + how +
        ": the missing physics is neither alone";
    Say(o, "discover: " + s.effect + " is not added: " + s.why_not_confirmed);
  }
}

}  // namespace

std::vector<CandidateScore> ScoreRound(const CandidatePass& pass, const ModelSnapshot& now,
                                       const std::vector<EstimationLog>& estimation,
                                       const DiscoveryOptions& o, int round) {
  std::vector<CandidateScore> scores = ScoreCandidates(
      pass, estimation, o.alpha, round, WeightedExcess(now.residual_tests, pass.fit.noise));
  for (const CandidateScore& s : scores) {
    char line[256];
    std::snprintf(line, sizeof(line),
                  "  %-18s F = %-10.4g p = %-10.3g p_holm = %-10.3g predicted share %-8.3g %s",
                  s.effect.c_str(), s.statistic, s.p_value, s.p_corrected, s.predicted_share,
                  !s.testable ? "not testable" : s.passes ? "passes" : "fails");
    Say(o, line);
  }
  return scores;
}

RoundRefits RefitShortlisted(const CandidatePass& pass, const ModelSnapshot& now,
                             const Vehicle& declared, const std::vector<std::string>& excluded,
                             const std::vector<EstimationLog>& estimation,
                             const std::vector<EstimationLog>& validation,
                             std::vector<CandidateScore>* scores, const DiscoveryOptions& o,
                             DiscoveryClock::time_point start) {
  std::vector<std::string> symptom_channels;
  std::map<std::string, std::vector<std::string>> distorted;
  for (const std::string& name : SymptomaticParameters(pass.fit.parameters, declared.parameters)) {
    distorted[name] = ChannelsReachedBy(pass.fitted, {name}, estimation, pass.fit.noise);
    for (const std::string& c : distorted[name]) symptom_channels.push_back(c);
  }
  MarkRestartsAtBounds(pass.fitted, declared, distorted, estimation, pass.fit.noise, scores);
  const std::vector<std::string> lost = LostChannels(now.fit, now.residual_tests, symptom_channels);
  const RoundShortlist list = Shortlist(*scores, symptom_channels, excluded, o.max_refits,
                                        o.min_share_of_excess, o.alpha, lost);
  if (!list.on_lost_channels.empty()) {
    Say(o, "  the fit at the bounds predicts " + Joined(lost) +
               " no better than their mean: every candidate acting there is refitted, those "
               "beyond the slots if none of the slots' is added");
  }
  for (int k : list.All()) {
    const CandidateScore& s = (*scores)[k];
    if (s.restart_values.empty()) continue;
    std::string names;
    for (const auto& [name, value] : s.restart_values) names += (names.empty() ? "" : ", ") + name;
    Say(o, "  " + s.effect +
               (s.blind_at_bounds ? " reaches the channels " + names +
                                        " distort only off their bounds"
                                  : " acts on channels that " + names + " distort") +
               ": its refit restarts them at the config values");
  }
  // The Wald level of every refit the round may run, whether or not those
  // on the lost channels are reached: a slot's refit qualifies as it would
  // beside them.
  const size_t family = list.first.size() + list.on_lost_channels.size();
  const std::map<std::string, double> at_bounds =
      ConfigValuesOfSymptomaticParameters(pass.fit.parameters, declared);
  RoundRefits r;
  r.shortlist = list.first;
  r.shortlist.insert(r.shortlist.end(), list.after_passing.begin(), list.after_passing.end());
  r.refits = RefitInRankOrder(pass, estimation, validation, now, r.shortlist, family, at_bounds,
                              scores, o, start, list.first.size(), lost);
  const RoundChoice slots =
      ChooseOfRound(Judged(r, *scores), WaldLevel(o, family), o.min_channels_excess,
                    o.decisive_share_of_all_excess, o.min_share_of_excess);
  // Those beyond the slots wait for them as the slots' own waiting ones do
  // (RefitInRankOrder). Measured (bench/discover_speed.sh, 41 flight-only
  // logs): the lost channels widened rounds to up to eleven refits in 15 of
  // the logs, among them every log beyond 20 s.
  std::vector<int> beyond;
  std::vector<std::string> still_lost = lost;
  if (slots.added >= 0) {
    const CandidateScore& added = (*scores)[r.shortlist[slots.added]];
    const ModelSnapshot& with_it = r.refits[slots.added].snapshot;
    still_lost = LostChannels(with_it.fit, with_it.residual_tests, lost);
    for (int k : list.on_lost_channels) {
      CandidateScore& s = (*scores)[k];
      if (ReachesAny(s.channels, still_lost)) {
        beyond.push_back(k);
        continue;
      }
      s.why_not_confirmed = "not refitted: " + added.effect +
                            ", refitted in the slots before it, qualifies; the next round tests "
                            "it against the model with " + added.effect;
      Say(o, "  refit " + s.effect + ": " + s.why_not_confirmed);
    }
  } else {
    beyond = list.on_lost_channels;
  }
  if (!beyond.empty()) {
    Say(o, slots.added >= 0
               ? StillLosesText((*scores)[r.shortlist[slots.added]].effect, still_lost) +
                     ": refitting those acting there"
               : "  none of the slots' refits is added: refitting those acting on the lost "
                 "channels");
    RoundRefits more;
    more.shortlist = beyond;
    more.refits = RefitInRankOrder(pass, estimation, validation, now, more.shortlist, family,
                                   at_bounds, scores, o, start);
    r.shortlist.insert(r.shortlist.end(), more.shortlist.begin(), more.shortlist.end());
    for (CandidateRefit& refit : more.refits) r.refits.push_back(std::move(refit));
  }
  ChooseAndSay(&r, family, scores, o);
  return r;
}

RoundRefits RefitListed(const CandidatePass& pass, const ModelSnapshot& now, const Vehicle& declared,
                        const std::vector<int>& listed, size_t family,
                        const std::vector<EstimationLog>& estimation,
                        const std::vector<EstimationLog>& validation,
                        std::vector<CandidateScore>* scores, const DiscoveryOptions& o,
                        DiscoveryClock::time_point start) {
  RoundRefits r;
  r.shortlist = listed;
  r.refits = RefitInRankOrder(pass, estimation, validation, now, r.shortlist, family,
                              ConfigValuesOfSymptomaticParameters(pass.fit.parameters, declared),
                              scores, o, start);
  ChooseAndSay(&r, family, scores, o);
  return r;
}

}  // namespace coaxid
