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
// "More" is material: the refit at a bound removes at least
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
  int dominant = -1;  // the refit at a bound that removes more, decisively
};

// wald_level: the round's Wald level (alpha over the refits);
// min_channels_excess, decisive_share, min_share_of_excess: DiscoveryOptions'.
RoundChoice ChooseOfRound(const std::vector<RefitOfRound>& refits, double wald_level,
                          double min_channels_excess, double decisive_share,
                          double min_share_of_excess);

}  // namespace coaxid
