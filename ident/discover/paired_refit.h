// Two effects the closing loop adds together (effects.md steps 4, 5 and 7;
// issue 13).
//
// A round that adds nothing may hold a refit that is significant and removes
// a material share of its channels' excess error (min_share_to_pair, 0.1),
// but carries one of its own parameters to a bound: the effect pushed past
// its range stands in for a second one beside it (measured, controllers'
// study seeds 8901 and 8902: a stabilizer bar beside a swashplate bias, the
// bar's T_b at its 10 s bound, its slow tilt taking the bias's place; the
// confusion study's 11966 and the controllers' 11031: a bar at its bound
// removing 0.196 and 0.144 beside a CG offset at the fit rate; no other
// candidate qualified alone). Or it may hold a refit that is not
// significant but removes materially more of the excess over all channels
// than the one that qualifies, which it held back (round_choice.h: wind
// beside a missing ground effect, seed 21253). The round is then refitted
// with that candidate (the first) in the
// model: every other candidate scored and the shortlisted ones refitted
// against the model with it, on the gates of discovery.h. The one chosen
// there (the second) is added with the first when, at their joint refit,
// the first's parameters are inside their bounds and significantly away
// from absence (cluster-robust Wald at the round's level), and the pair
// removes at least min_share_of_excess of their channels' excess error
// against the model with neither, on the estimation and the held-out data.
// The loop judges step 5 again after (either member the other makes
// redundant leaves). When the pair is not added and the second had no refit
// in the round (the first took its slot), the second is refitted alone
// against the current model and judged like any candidate of the round (its
// Wald level counting one refit more): added if it qualifies. When the
// second did qualify alone in the round but was held back by the first's
// dominance (round_choice.h), and beside it the first stays at its bound or
// is not significant, the second is added from its own refit of the round.
// Nothing else changes: a round that adds a single effect, or holds no such
// refit, is not refitted again.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "ident/discover/round_refits.h"

namespace coaxid {

struct PairedRefit {
  bool added = false;                  // the pair is added
  bool second_alone = false;           // not the pair: the second alone is (joint: its refit)
  std::string first, second;           // effects; empty: none tried / none chosen
  std::vector<CandidateScore> beside;  // the candidates scored with the first in the model
  CandidateRefit joint;                // the second's refit with the first (added: the model)
  double share_of_excess = 0;          // of the pair's channels, against the model with neither
  double share_of_excess_held_out = std::numeric_limits<double>::quiet_NaN();
  double first_wald_p_value = 1;       // the first's Wald test at the joint refit
  std::string why_not;                 // not added, a first tried: why
};

// A refused pair's second added from its own refit of the round: the index
// into round.refits of the refit the round held back (round_choice.h
// `vetoed`) when it is the second's (`second`, an index into the round's
// scores) and beside the second the first is not an effect (at its bound or
// not significant); -1 otherwise.
int VetoedRefitOfTheSecond(const RoundRefits& round, int second, bool first_not_an_effect);

// `round`: the refits of a round against the current model (`pass`, `now`)
// that chose nothing, `scores` the round's scores (the first's score is updated when
// the pair is added). `excluded`: removed effects not yet allowed back (ExcludedEffects).
PairedRefit RefitBesideABound(const CandidatePass& pass, const ModelSnapshot& now,
                              const RoundRefits& round,
                              std::vector<CandidateScore>* scores, const Vehicle& declared,
                              const std::vector<std::string>& excluded,
                              const std::vector<EstimationLog>& estimation,
                              const std::vector<EstimationLog>& validation,
                              const DiscoveryOptions& o, int round_number,
                              DiscoveryClock::time_point start);

}  // namespace coaxid
