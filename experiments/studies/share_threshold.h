// How discover's practical-significance threshold (DiscoveryOptions::
// min_share_of_excess, effects.md step 5) is chosen from a randomised study
// (issue 13): each run's record lists its refits with their gates and shares
// (experiments/studies/run.cc). For each threshold t of a grid this counts,
// over the round-1 refits (against the declared model, the only round whose
// refits do not depend on what earlier rounds added):
//   true_qualify   refits of an effect in the truth that pass every gate but
//                  the share (significant) and remove at least t of their
//                  channels' excess, on the estimation and the held-out data;
//   false_qualify  the same for effects the truth lacks;
//   wrong_choice   runs whose round-1 choice at t (the qualifying refit that
//                  removes the most excess over all channels, as the loop
//                  ranks) is an effect the truth lacks;
//   true_lost      runs with a significant true refit where nothing
//                  qualifies at t.
// It replays the decision on the refits the loop ran at its own threshold:
// the shortlist (half the threshold, predicted) and the refits stopped by a
// decisive one are those of the study's threshold, and the held-out share is
// computed only for refits that qualified on the estimation data (below the
// study's threshold the estimation share stands in for it: an upper bound
// on what would qualify). A refit below DiscoveryOptions::
// min_share_to_reweight (0.05) at the current weights is rejected before its
// Wald test: at the grid's thresholds up to 0.2 such a refit counts as not
// significant, though its re-weighting could have raised its share (measured,
// from 0.016 to 0.198 at most).
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace coaxid {

nlohmann::json ShareThresholdSummary(const std::vector<nlohmann::json>& records);
std::string ShareThresholdMarkdown(const nlohmann::json& summary);

}  // namespace coaxid
