// The discover confusion table of a randomised study (issue 13): per run the
// truth drawn (experiments/studies/random_draw.h) against what discover added
// and whether it reported channels unexplained, and the rates the loop is
// judged by, for all runs and split into flight-only and flight + balance:
//   single_found_alone   per library effect: runs with that effect alone in
//                        the truth where discover added exactly it;
//   single_found_alone_visible  the same over the runs where the effect is
//                        visible: the declared model's fit leaves some
//                        channel's rms at least kVisibleRmsOverNoise x its
//                        sample-to-sample noise (below that no method can see
//                        it: the declared parameters absorb it);
//   nothing_wrong_added  all runs: nothing added that the truth lacks;
//   outside_nothing_added  outside-library truths: nothing added;
//   outside_unexplained  ... and at least one channel reported unexplained
//                        (and over the visible runs);
//   none_false_alarm     no-effect truths: something added;
//   pair_both_found      two-effect truths: exactly both added.
// Each rate with its Wilson 95 % interval.
#pragma once

#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace coaxid {

// With n >= 6000 samples a channel's rms / noise of a white residual scatters
// by about 1 / sqrt(2 n) < 1 %: 1.1 is a misfit, not chance. The ratio at
// which discover calls a structured channel unexplained
// (DiscoveryOptions::unexplained_rms_ratio; a test holds them equal).
inline constexpr double kVisibleRmsOverNoise = 1.1;

// Records of a randomised study with method discover; runs without a draw or
// whose discover failed are counted under "failed".
nlohmann::json ConfusionSummary(const std::vector<nlohmann::json>& records);
// The library effects of a randomised run's truth, from its record's `draw`
// (empty for no effect and for a load outside the library).
std::set<std::string> TruthEffectsOfDraw(const nlohmann::json& draw);
std::string ConfusionMarkdown(const nlohmann::json& confusion);

}  // namespace coaxid
