// Which candidate effects the closing loop refits in a round (effects.md,
// steps 5-7): the nonlinear refits are the loop's cost, so at most a few per
// group, in order of promise.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/statistics.h"
#include "ident/discover/candidate_scores.h"
#include "ident/discover/residual_analysis.h"

namespace coaxid {

// The channels of `symptom_channels` (distorted by parameters at a bound or
// far outside their range) that the fit has lost: it predicts them no better
// than their mean (nrmse >= kUnexplainedNrmse) and their residual is
// kLostChannelRms times their noise or more, a signal of their own the fit
// does not follow rather than a channel that holds little besides noise
// (measured: hover's ax, ay at nrmse 0.95-0.97 and 1.0-1.2 x their noise;
// p, q of seeds 9537, 9573, 10339 at nrmse 0.94-1.01 and 3.0-6.6 x).
inline constexpr double kLostChannelRms = 2.0;
std::vector<std::string> LostChannels(const std::map<std::string, FitError>& fit,
                                      const std::vector<ChannelResidualTest>& residual_tests,
                                      const std::vector<std::string>& symptom_channels);

// The candidates to refit (indices into scores), none of `excluded` (removed
// effects not yet allowed back, ExcludedEffects): at most max_refits of those
// that pass the linearised test; then, if the current fit holds parameters at a
// bound (step 7), at most max_refits more, restarted off the bounds: first
// those blind at the bounds (measured: an undeclared wind with Cx, Cy pressed
// to 0, flight only, never refitted), then the passing ones the first slots
// left out that act on a channel those parameters distort, in their rank
// (measured, confusion seed 21387, a swashplate bias and wind, low flight,
// five parameters at bounds, six candidates passing: the bias and the wind,
// passing at p 1e-15 and 2e-6, lost their slots to three that failed their
// score test, were never refitted, and nothing was added in 33-38 s; taking
// the slots first, both are added in 25 s), then the testable ones acting on a
// channel those parameters distort (`symptom_channels`): the linearisation at a
// bound is a poor guide (measured: an undeclared ground effect at 0.13-0.9 m,
// Cz pressed at its bound, predicted to remove 2 % of the excess, 90 % at the
// refit; an undeclared CG offset with d and Iyy at bounds, never shortlisted
// while three passing candidates filled the slots); then, up to max_refits in
// all, the testable ones predicted to remove at least half of
// min_share_of_excess. Largest predicted share first within each group; a share
// above 1 (the linearised step would fit the channels below their noise) from
// a step that left the candidate's bounds (beyond_linear_range) says the
// linearisation failed, not how promising the candidate is, and ranks last
// in its group (measured, seed 8000 of discover_controllers.yaml: an undeclared
// ground effect, Cz at 0; wake_interference "predicted" 406 %, its step
// clipped to 0 in both parameters, and took the slot ground_effect, at
// 0.6 %, needed). A share above 1 from a step inside the
// bounds ranks by its share: the drop it predicts includes the segments'
// continuity ties, which the channels' excess leaves out (measured: seed 9349
// of the controllers study, 9607 and 11018 of the confusion study, an
// undeclared ground effect, flight only, Cz at its upper bound: shares 528 %,
// 447 %, 341 %, each drop 95-98 % of the excess and the ties' weighted RSS
// together; linearised k_ge 0.921, 1.110, 1.316 against the truth's 0.935,
// 1.119, 1.375. Ranked last, 9607 and 11018 added nothing). The share and
// the score test rank
// candidates differently, and each has ranked a run's effect out of its
// slots (docs/discover_confusion.md, "Ranking the candidates at a bound by
// their score test: tried, reverted"): the testable candidate with the
// smallest score-test p-value, if below alpha (uncorrected), is refitted as
// well when the shares leave it out. The score is taken at the null, where
// it holds whatever the linearised step does (measured: seed 9349 of the
// controllers study, an undeclared ground effect, flight only, Cz at its
// upper bound: ground_effect's p = 0.0012, the round's smallest, a predicted
// share of 528 %, then ranked last whatever its step; wind, accel_bias and
// motor_lag took the three slots and nothing was added. Seed 9379,
// gyroscopic moments and rotor damping with
// the balance log, no parameter at a bound: gyroscopic's p = 0.0011 (0.014
// after Holm), predicted 12 %, nothing shortlisted, nothing added; refitted,
// it removes 70 %). Where a bound leaves the score no power (every p-value
// 0.5-1) nothing is added to the shortlist.
// Where the fit at the bounds has lost channels (`lost_channels`: those it
// predicts no better than their mean, with a residual kLostChannelRms times
// their noise), its linearisation says nothing about
// which candidate acts there: every testable one acting on a symptom channel
// and on a lost one is refitted, beyond the slots (measured: seeds 9573 and
// 9537 of the controllers study, a stabilizer bar and a swashplate bias,
// flight only, low flight: the declared fit pressed Ixx, Iyy to their upper
// bound and left p, q at nrmse 0.97-1.01; the bar ranked sixth by its share,
// the bias last (a share of 152 %), neither was refitted, nothing added).
// They are refitted after the others, and only when none of those is added
// (RefitShortlisted): a round that finds its effect among the slots does
// not need them, unless the fit with the one it finds still loses some of
// them (LostChannels at its refit): then those acting on a channel still
// lost are refitted too, and the round chooses among them all (measured,
// seed 22946 of discover_controllers.yaml, 60 s, flight only, hover, a CG
// offset beside a stabilizer bar at T_b = 1.9 s, the declared fit with Ixx
// and Iyy at their upper bound and p, q, ax lost: wind, blind at the bounds,
// qualified on u, v, w, ax, ay, az and left p, q lost, and the bar, waiting
// for the slots, was never refitted in round 1; wind was added, p and q
// stayed unexplained in 38.6 s. Refitted, the bar takes T_b to its bound and
// removes 91 % of the excess over all channels, holds wind back
// (round_choice.h) and is added with the CG offset as a pair, in 13-15 s).
// Where some candidates pass their score test, the at-bounds slots' ones
// (passing beyond the first slots, or failing it, shortlisted for acting on
// a distorted channel) count only if none of the first slots' refits is
// added, or the fit with the one added still loses a channel they act on
// (`after_passing`; they are
// refitted after those, and only then): the
// next round tests them against the model with it (measured, seed 20622 of
// bench/discover_speed.sh, gyroscopic moments and rotor damping, flight only,
// Ixx, Iyy, Izz far outside their range: gyroscopic passed and qualified;
// cg_offset, swashplate_bias and motor_lag, refitted beside it for 23 s of
// CPU, were rejected). Where none passes they are refitted with the rest: the
// stabilizer bar at a bound often fails its score test and is found only so.
struct RoundShortlist {
  std::vector<int> first;             // the slots, and the most significant
  std::vector<int> after_passing;     // the at-bounds slots' ones, when some pass
  std::vector<int> on_lost_channels;  // beyond the slots, acting on a lost channel
  std::vector<int> All() const;       // first, after_passing, then on_lost_channels
};
RoundShortlist Shortlist(const std::vector<CandidateScore>& scores,
                         const std::vector<std::string>& symptom_channels,
                         const std::vector<std::string>& excluded, int max_refits,
                         double min_share_of_excess, double alpha,
                         const std::vector<std::string>& lost_channels = {});

}  // namespace coaxid
