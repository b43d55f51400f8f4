// One round of the closing loop (effects.md steps 3-6), in the pieces the
// loop (discovery.cc) and the paired refit (paired_refit.h) share: score
// every candidate against the current model, refit the shortlisted ones one
// at a time in rank order, judge each refit on the gates of discovery.h, and
// choose what the round adds (round_choice.h).
#pragma once

#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "ident/discover/candidate_scores.h"
#include "ident/discover/discovery.h"
#include "ident/discover/round_choice.h"
#include "ident/estimation_log.h"

namespace coaxid {

using DiscoveryClock = std::chrono::steady_clock;

// A progress line, if the options ask for them.
void Say(const DiscoveryOptions& o, const std::string& line);

// task(0) ... task(n - 1), each once, on `workers` threads (this one among
// them), taken in order as threads come free. A worker that finds no task
// left adds its worker_options.num_threads to worker_options.spare_threads,
// where the fits still running borrow them.
void SideBySide(int n, int workers, const OutputErrorOptions& worker_options,
                const std::function<void(int)>& task);

// How n fits run side by side on fit.num_threads threads: the number of
// workers (at most n), and in *worker each one's fit options, its share of
// the threads and the pool the workers' threads go to as they finish
// (spare_threads.h), silent (the loop reports each result).
int SideBySideWorkers(int n, const OutputErrorOptions& fit, OutputErrorOptions* worker);

// The held-out side of a snapshot (nothing without held-out logs).
void AddValidation(const std::vector<EstimationLog>& validation, const DiscoveryOptions& o,
                   ModelSnapshot* s);

// The same for a model the loop only tries (a candidate's refit, the model
// without an added effect, the model at a first effect's bound): why it
// cannot be simulated on the held-out logs (empty: it can, and *s has its
// held-out side). That is the tried model's failure, not the run's (seed
// 13269 of the confusion study: the model without its CG offset, once
// gyroscopic moments were added, ended the run).
std::string TryAddValidation(const std::vector<EstimationLog>& validation,
                             const DiscoveryOptions& o, ModelSnapshot* s);

// A fitted model and how well it fits the estimation (and held-out) logs.
ModelSnapshot Snapshot(const Vehicle& vehicle, const OutputErrorResult& r,
                       const std::vector<EstimationLog>& estimation,
                       const std::vector<EstimationLog>& validation, const DiscoveryOptions& o);

// The Wald level of a round's refits: alpha over the number refitted.
double WaldLevel(const DiscoveryOptions& o, size_t refitted);

// Why a refitted candidate fails a gate before practical significance (empty:
// none): the Wald test at `level`, physical meaning, an excess to remove.
std::string WhyNotSignificant(const CandidateScore& s, double level, const DiscoveryOptions& o);

// Why a refitted candidate is not added (empty: it is), at the Wald level
// `level`. Without a held-out share (NaN: no held-out logs, or none whose
// channels can judge it) the last gate reads the estimation
// share alone; the held-out share only ever adds a condition to that gate.
std::string WhyNotConfirmed(const CandidateScore& s, double level, const DiscoveryOptions& o);

// What a candidate's refit gives the loop: the model with it and the pass
// at the refit (the next round's, if it is added).
struct CandidateRefit {
  bool ok = false;
  double seconds = 0;
  double share_of_all_excess = 0;  // of the excess error over all channels, estimation data
  ModelSnapshot snapshot;
  CandidatePass next;
};

// Every candidate of `pass` scored against the current model `now` (round
// `round`), one progress line each.
std::vector<CandidateScore> ScoreRound(const CandidatePass& pass, const ModelSnapshot& now,
                                       const std::vector<EstimationLog>& estimation,
                                       const DiscoveryOptions& o, int round);

// A round's refits and what it adds.
struct RoundRefits {
  std::vector<int> shortlist;          // indices into the round's scores
  std::vector<CandidateRefit> refits;  // one per shortlisted candidate
  RoundChoice choice;                  // indices into shortlist / refits
};

// Shortlists the candidates of `*scores` (none of `excluded`), restarting the
// declared parameters (config values in `declared`) that the current fit
// left at a bound or far outside their range, refits them one at a time in
// rank order (up to one that decides the round) against `now` and chooses
// (ChooseOfRound). The slots' symptomatic ones
// (RoundShortlist::after_passing), then those beyond the slots on the
// channels the fit has lost (RoundShortlist::on_lost_channels), are refitted
// only when none of those refitted before them is added. Fills the scores'
// refit fields.
RoundRefits RefitShortlisted(const CandidatePass& pass, const ModelSnapshot& now,
                             const Vehicle& declared, const std::vector<std::string>& excluded,
                             const std::vector<EstimationLog>& estimation,
                             const std::vector<EstimationLog>& validation,
                             std::vector<CandidateScore>* scores, const DiscoveryOptions& o,
                             DiscoveryClock::time_point start);

// The candidates `listed` (indices into *scores, restarts marked by an
// earlier RefitShortlisted of the same scores) refitted in rank order against
// `now` and judged at the Wald level of `family` refits (at least as many
// as listed): what RefitShortlisted does once it has its shortlist.
RoundRefits RefitListed(const CandidatePass& pass, const ModelSnapshot& now, const Vehicle& declared,
                        const std::vector<int>& listed, size_t family,
                        const std::vector<EstimationLog>& estimation,
                        const std::vector<EstimationLog>& validation,
                        std::vector<CandidateScore>* scores, const DiscoveryOptions& o,
                        DiscoveryClock::time_point start);

}  // namespace coaxid
