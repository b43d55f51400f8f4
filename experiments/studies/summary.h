// A study's summary (docs/study.md): per sweep point, method and parameter,
// the bias, the spread (sample std of the estimates), the mean reported std,
// their ratio, and the coverage of the 95 % intervals (estimate +- 1.96 std
// holds the truth) with the binomial 95 % band of that count for the runs
// there are; for discover, the detection rate of each effect the truth has
// and the config does not declare, and the false-alarm rate (runs adding an
// effect the truth does not have). Computed from the records in run order,
// so it does not depend on the order the runs finished in.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "experiments/studies/spec.h"

namespace coaxid {

constexpr double kNominalCoverage = 0.95;
constexpr double kIntervalHalfWidthInStd = 1.959963984540054;  // two-sided 95 % normal

// [lo, hi]: the central 95 % range of a Binomial(n, p) count: P(X < lo) <=
// 2.5 % and P(X > hi) <= 2.5 %, each the tightest such bound. n = 0 gives [0, 0].
std::pair<int, int> BinomialBand(int n, double p, double confidence = 0.95);

// count of n as {"count", "runs", "rate", "interval": Wilson 95 % [lo, hi]}
// (rate and interval null when n = 0).
nlohmann::json RateJson(int count, int n);

nlohmann::json SummarizeStudy(const StudySpec& spec, const std::vector<nlohmann::json>& records);
std::string StudySummaryMarkdown(const nlohmann::json& summary);

}  // namespace coaxid
