#include "ident/discover/round_choice.h"

namespace coaxid {

RoundChoice ChooseOfRound(const std::vector<RefitOfRound>& refits, double wald_level,
                          double min_channels_excess, double decisive_share,
                          double min_share_of_excess) {
  RoundChoice c;
  for (size_t k = 0; k < refits.size(); ++k) {
    const RefitOfRound& r = refits[k];
    if (!r.judged) continue;
    const CandidateScore& s = *r.score;
    const int i = static_cast<int>(k);
    if (s.confirmed && (c.added < 0 || s.excess_removed_all_channels >
                                           refits[c.added].score->excess_removed_all_channels)) {
      c.added = i;
    }
    const bool significant = s.wald_p_value < wald_level;
    const bool dominant_at_bound = !s.plausible && significant &&
                                   s.channels_excess >= min_channels_excess &&
                                   r.share_of_all_excess >= decisive_share;
    const bool dominant_not_significant = !significant &&
                                          s.channels_excess >= min_channels_excess &&
                                          r.share_of_all_excess >= min_share_of_excess;
    if ((dominant_at_bound || dominant_not_significant) &&
        (c.dominant < 0 || r.share_of_all_excess > refits[c.dominant].share_of_all_excess)) {
      c.dominant = i;
    }
  }
  // The excess over all channels the best qualifying refit leaves, and how
  // much of it the dominant one removes.
  const auto removes_materially_more = [&] {
    const double left = 1 - refits[c.added].share_of_all_excess;
    const double more =
        refits[c.dominant].share_of_all_excess - refits[c.added].share_of_all_excess;
    return more > 0 && more >= min_share_of_excess * left;
  };
  if (c.added >= 0 && c.dominant >= 0 && removes_materially_more()) {
    c.vetoed = c.added;
    c.added = -1;
  } else {
    c.dominant = -1;
  }
  return c;
}

}  // namespace coaxid
