// The discover confusion table of a randomised study (issue 13): per run the
// truth drawn (experiments/studies/random_draw.h) against what discover added
// and whether it reported channels unexplained, and the rates the loop is
// judged by, for all runs and split into flight-only and flight + balance:
//   single_found_alone   per library effect: runs with that effect alone in
//                        the truth where discover added exactly it;
//   nothing_wrong_added  all runs: nothing added that the truth lacks;
//   outside_unexplained  outside-library truths: nothing added and at least
//                        one channel reported unexplained;
//   none_false_alarm     no-effect truths: something added;
//   pair_both_found      two-effect truths: exactly both added.
// Each rate with its Wilson 95 % interval.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace coaxid {

// Records of a randomised study with method discover; runs without a draw or
// whose discover failed are counted under "failed".
nlohmann::json ConfusionSummary(const std::vector<nlohmann::json>& records);
std::string ConfusionMarkdown(const nlohmann::json& confusion);

}  // namespace coaxid
