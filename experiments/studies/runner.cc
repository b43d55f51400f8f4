#include "experiments/studies/runner.h"

#include <atomic>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <exception>
#include <mutex>
#include <thread>

#include "core/stopwatch.h"
#include "experiments/studies/run.h"

namespace coaxid {
namespace {

volatile std::sig_atomic_t g_stop = 0;

extern "C" void OnStopSignal(int signal) {
  g_stop = 1;
  std::signal(signal, SIG_DFL);  // a second one ends the process
}

std::string Duration(double seconds) {
  char text[48];
  if (seconds < 90) {
    std::snprintf(text, sizeof text, "%.0f s", seconds);
  } else if (seconds < 5400) {
    std::snprintf(text, sizeof text, "%.0f min %02.0f s", std::floor(seconds / 60),
                  std::fmod(seconds, 60));
  } else {
    std::snprintf(text, sizeof text, "%.1f h", seconds / 3600);
  }
  return text;
}

}  // namespace

void InstallStudyStopHandler() {
  g_stop = 0;
  std::signal(SIGINT, OnStopSignal);
  std::signal(SIGTERM, OnStopSignal);
}

bool StudyStopRequested() { return g_stop != 0; }

std::vector<int> PendingRuns(const StudySpec& spec, const std::set<std::string>& done, int shard,
                             int shards) {
  std::vector<int> pending;
  for (int i = shard; i < spec.NumRuns(); i += shards) {
    const StudyRunId id = RunIdAt(spec, i);
    if (!done.count(RunKey(id.point, id.seed_index))) pending.push_back(i);
  }
  return pending;
}

StudyRunnerResult RunStudyRuns(const StudySpec& spec, const std::vector<int>& pending,
                               RecordAppender* out, const StudyRunnerOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const long limit = options.max_runs < 0
                         ? static_cast<long>(pending.size())
                         : std::min<long>(options.max_runs, static_cast<long>(pending.size()));
  std::atomic<long> next{0};
  std::mutex mutex;  // guards done, error and the progress line
  int done = 0;
  double last_line = -1;  // elapsed at the last progress line [s]
  std::exception_ptr error;
  auto worker = [&] {
    for (;;) {
      if (StudyStopRequested()) return;
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (error) return;
      }
      const long k = next++;
      if (k >= limit) return;
      const StudyRunId id = RunIdAt(spec, pending[k]);
      try {
        const nlohmann::json record = RunStudyRun(spec, id);
        out->Append(record);
        std::lock_guard<std::mutex> lock(mutex);
        ++done;
        const double elapsed = SecondsSince(start);
        const long left = limit - done;
        // One line per run, at most one a second for fast runs; always the last.
        if (elapsed - last_line < 1.0 && left > 0) continue;
        last_line = elapsed;
        std::fprintf(stderr,
                     "%s: %d/%d runs done (%d this session, %s), elapsed %s, about %s left\n",
                     options.label.c_str(), options.done_before + done, options.total, done,
                     RunKey(id.point, id.seed_index).c_str(), Duration(elapsed).c_str(),
                     Duration(elapsed / done * left).c_str());
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!error) error = std::current_exception();
        return;
      }
    }
  };
  const int threads = std::max(1, std::min<int>(options.jobs, static_cast<int>(limit)));
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  StudyRunnerResult result;
  result.done = done;
  result.interrupted = StudyStopRequested();
  result.seconds = SecondsSince(start);
  return result;
}

}  // namespace coaxid
