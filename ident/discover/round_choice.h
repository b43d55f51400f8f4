// What a round of the closing loop adds (effects.md steps 5-6), once its
// refits are judged: of the refits that qualify (CandidateScore::confirmed),
// the one that removes the most excess error over all channels (two
// candidates can each remove all of their own channels' excess; they differ
// in what else they fix).
//
// Except when a refit removes at least the decisive share of the excess over
// all channels, significantly, but with one of its own parameters at a bound
// (not physically meaningful) and more of it than the best qualifying one:
// then nothing is added. The missing physics looks like that effect pushed
// past its range (a second effect beside it, or one outside the library),
// and a candidate that removes less is no explanation of it. Measured on the
// controllers' study (seeds 8901, 8902: stabilizer_bar + swashplate_bias in
// the truth): the bar alone took T_b to its bound 10 s, its slow tilt
// standing in for the bias, and removed 98 % of the excess over all
// channels; wind, removing 27 % (8901), qualified and was added.
// The same holds for a refit that is not significant (its cluster-robust
// Wald test fails) but removes at least min_share_of_excess of the excess
// over all channels, and materially more than the best qualifying one: the
// test fails because the physics beside it is missing from the model, whose
// structured residual inflates the robust variance, and the qualifying one
// is a stand-in for part of it. Measured on the slowest logs of the speed
// bench (wind beside a second effect, low flight, Cx at its bound): seed
// 21253 (wind + ground effect), wind's refit removed 96 % of the excess over
// all channels at Wald p = 0.025 (level 0.002) and accel_bias, 3 %, was
// added, to be removed two rounds later (34 s); controllers' 11086 (wind +
// stabilizer bar), wind 56 % at p = 0.027, accel_bias 2 % added (73 s).
// Nothing is added on the veto's word: the round then refits the candidates
// it held back for a qualifying one (round_refits.h), where a better one may
// qualify (11086: the bar, 46 %, which wind's 56 % does not veto), and if
// none is chosen it goes to the paired refit (paired_refit.h), where the
// dominant refit must be significant beside a second effect, or the
// held-back one is added from its own refit (21253: wind and ground_effect
// together, 25 s).
// "More" is material: the dominant refit removes at least
// min_share_of_excess of the excess the best qualifying one leaves (the
// practical-significance threshold, discovery.h). A look-alike that removes
// as much is no sign of other physics (measured, confusion study seed 11114,
// a swashplate bias alone, flight only: the bias qualified, 93.4 % of all
// channels' excess, 95.9 % of its channels' held out; the bar at T_b = 10 s
// removed 93.5 % and vetoed it; beside the bar gyro_bias was chosen, the
// bar stayed at its bound, and nothing was added).
#pragma once

#include <vector>

#include "ident/discover/candidate_scores.h"

namespace coaxid {

struct RefitOfRound {
  const CandidateScore* score = nullptr;  // its gates decided (confirmed, plausible, ...)
  bool judged = false;                    // the refit ran to its end
  double share_of_all_excess = 0;         // of the excess error over all channels removed
};

struct RoundChoice {
  int added = -1;     // index into the refits; -1: nothing is added
  int vetoed = -1;    // the best qualifying refit, not added because of `dominant`
  int dominant = -1;  // the refit at a bound (or not significant) that removes materially more
};

// wald_level: the round's Wald level (alpha over the refits);
// min_channels_excess, decisive_share, min_share_of_excess: DiscoveryOptions'.
RoundChoice ChooseOfRound(const std::vector<RefitOfRound>& refits, double wald_level,
                          double min_channels_excess, double decisive_share,
                          double min_share_of_excess);

}  // namespace coaxid
