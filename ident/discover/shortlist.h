// Which candidate effects the closing loop refits in a round (effects.md,
// steps 5-7): the nonlinear refits are the loop's cost, so at most a few per
// group, in order of promise.
#pragma once

#include <string>
#include <vector>

#include "ident/discover/candidate_scores.h"

namespace coaxid {

// The candidates to refit (indices into scores), none of `excluded` (removed
// effects do not come back): at most max_refits of those that pass the
// linearised test; then, if the current fit holds parameters at a bound
// (step 7), at most max_refits more, restarted off the bounds: first those
// blind at the bounds (measured: an undeclared wind with Cx, Cy pressed to 0,
// flight only, never refitted), then the testable ones acting on a channel
// those parameters distort (`symptom_channels`): the linearisation at a bound
// is a poor guide (measured: an undeclared ground effect at 0.13-0.9 m, Cz
// pressed at its bound, predicted to remove 2 % of the excess, 90 % at the
// refit; an undeclared CG offset with d and Iyy at bounds, never shortlisted
// while three passing candidates filled the slots); then, up to max_refits in
// all, the testable ones predicted to remove at least half of
// min_share_of_excess, largest predicted share first; a share above 1 (the
// linearised step would fit the channels below their noise) says the
// linearisation failed, not how promising the candidate is, and ranks last.
// The candidates acting on distorted channels rank by their score test's
// p-value, smallest first: at a bound the linearised step's size is no guide
// either way. Measured: seed 8000 of discover_controllers.yaml (an
// undeclared ground effect with the balance log, Cz at 0), binary a766d57:
// wake_interference "predicted" 406 % and took the slot ground_effect, at
// 0.6 %, needed; seed 9607 of discover_confusion.yaml (the same truth,
// flight only, Cz at 5), binary 96745f1: ground_effect, whose p = 0.011 was
// the round's smallest, "predicted" 447 % and ranked behind wind, accel_bias
// and motor_lag (0.01-19 %), which took the three slots; nothing was added.
std::vector<int> Shortlist(const std::vector<CandidateScore>& scores,
                           const std::vector<std::string>& symptom_channels,
                           const std::vector<std::string>& excluded, int max_refits,
                           double min_share_of_excess);

}  // namespace coaxid
