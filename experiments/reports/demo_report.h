// The one report of `coaxid demo`: the whole story on the shipped data, as
// Markdown (DIR/report.md) and the same as a self-contained HTML page
// (DIR/report.html, experiments/reports/markdown_html.h). Sections per step:
// simulation and reproducibility, the paper's linear baseline, output error,
// the EKF (each: estimates against the truth, key plots), the comparison of
// the three (experiments/reports/compare_table.h), and discover on a simulated log with
// an undeclared effect and on measured test-stand data (error before/after).
// Pure: from what the demo ran to text; paths are relative to DIR.
#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace coaxid {

struct DemoSimulatedLog {
  std::string scenario;
  uint64_t seed = 0;
  std::string log, truth;  // relative to DIR
  int rows = 0;
  double duration_s = 0;   // simulated time
  std::string reproduced;  // against the shipped log
};

struct DemoDiscovery {
  std::string folder;  // relative to DIR
  std::string title;   // what the logs are
  std::vector<std::string> logs;
  nlohmann::json discovery;  // its discovery.json
};

struct DemoRecord {
  std::string config;  // the vehicle config used
  std::vector<DemoSimulatedLog> simulated;
  std::string compare_folder;                     // relative to DIR
  nlohmann::json comparison;                      // compare.json
  std::map<std::string, nlohmann::json> reports;  // method -> its report.json
  std::vector<DemoDiscovery> discoveries;
  std::vector<std::pair<std::string, double>> step_seconds;  // wall time per step
  double total_s = 0;
};

// report.md.
std::string DemoReportMarkdown(const DemoRecord& record);

}  // namespace coaxid
