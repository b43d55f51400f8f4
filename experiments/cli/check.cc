#include "experiments/cli/check.h"

#include <iostream>
#include <string>
#include <vector>

#include "core/errors.h"
#include "core/log.h"
#include "experiments/cli/cli.h"
#include "experiments/cli/flag_checks.h"
#include "experiments/cli/flags.h"
#include "experiments/cli/identify.h"
#include "experiments/reports/log_summary.h"

namespace coaxid {

int RunCheck() {
  RequireFlag(FLAGS_logs, "logs", kCliUsage);
  const std::vector<std::string> paths = SplitList(FLAGS_logs);
  if (paths.empty()) throw InputError("--logs names no file");
  std::vector<Log> logs;
  for (const std::string& path : paths) logs.push_back(ReadLog(path));
  for (const Log& log : logs) {
    const nlohmann::json summary = SummarizeLog(log);
    std::cout << SummaryMarkdown(log.source, summary);
  }
  std::cout << LinearKfCheckText(logs, FLAGS_config);
  std::cout << "check: " << logs.size() << " log(s) valid\n";
  return 0;
}

}  // namespace coaxid
