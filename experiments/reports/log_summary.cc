#include "experiments/reports/log_summary.h"

#include <cmath>
#include <cstdio>

#include "core/statistics.h"

namespace coaxid {

nlohmann::json SummarizeLog(const Log& log) {
  nlohmann::json columns = nlohmann::json::array();
  for (size_t c = 0; c < log.columns.size(); ++c) {
    const std::vector<double>& v = log.values[c];
    double lo = INFINITY, hi = -INFINITY;
    int missing = 0;
    for (double x : v) {
      if (std::isnan(x)) {
        ++missing;
        continue;
      }
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
    columns.push_back({{"name", log.columns[c]},
                       {"min", lo},
                       {"max", hi},
                       {"mean", Mean(v)},
                       {"std", StdDev(v)},
                       {"missing", missing}});
  }
  const auto& t = log.Column("t");
  return {{"kind", LogKindName(log.kind)},
          {"source", log.source},
          {"rows", log.NumRows()},
          {"duration_s", log.NumRows() > 0 ? t.back() - t.front() : 0.0},
          {"columns", columns}};
}

std::string SummaryMarkdown(const std::string& title, const nlohmann::json& summary) {
  std::string out = "### " + title + "\n\n";
  char line[256];
  std::snprintf(line, sizeof line, "%s log, %d rows, %.3f s.\n\n",
                summary["kind"].get<std::string>().c_str(), summary["rows"].get<int>(),
                summary["duration_s"].get<double>());
  out += line;
  out += "| column | min | max | mean | std | missing |\n|---|---|---|---|---|---|\n";
  for (const auto& c : summary["columns"]) {
    auto num = [](const nlohmann::json& j) {
      return j.is_number() ? j.get<double>() : std::nan("");
    };
    std::snprintf(line, sizeof line, "| %s | %.5g | %.5g | %.5g | %.3g | %d |\n",
                  c["name"].get<std::string>().c_str(), num(c["min"]), num(c["max"]),
                  num(c["mean"]), num(c["std"]), c["missing"].get<int>());
    out += line;
  }
  return out + "\n";
}

}  // namespace coaxid
