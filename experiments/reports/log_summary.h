// A short human-readable summary of a log: kind, size, and per column the
// range, mean, standard deviation and missing count. Used by `check` and `demo`.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "core/log.h"

namespace coaxid {

nlohmann::json SummarizeLog(const Log& log);
// One Markdown table of the summary.
std::string SummaryMarkdown(const std::string& title, const nlohmann::json& summary);

}  // namespace coaxid
