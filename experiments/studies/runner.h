// Runs a study's pending runs on a pool of threads (each run single-threaded
// inside), appending each record to runs.jsonl (or a part file) the moment it
// finishes, with progress and the estimated time left on stderr (a line per
// finished run, at most one a second).
// SIGINT / SIGTERM stop the study cleanly: no new run starts, the runs in
// flight finish and are written; a second signal ends the process at once
// (the finished runs are on disk either way). Rerunning resumes.
#pragma once

#include <string>
#include <vector>

#include "experiments/studies/records.h"
#include "experiments/studies/spec.h"

namespace coaxid {

// Indices of the runs of shard `shard` of `shards` (run i belongs to shard
// i mod shards) that are not in `done`.
std::vector<int> PendingRuns(const StudySpec& spec, const std::set<std::string>& done,
                             int shard = 0, int shards = 1);

struct StudyRunnerOptions {
  int jobs = 1;                 // worker threads
  long max_runs = -1;           // stop after this many runs (< 0: all pending)
  std::string label = "study";  // progress prefix
  int done_before = 0;          // runs finished in earlier sessions (for the progress line)
  int total = 0;                // runs of the whole study (or shard)
};

struct StudyRunnerResult {
  int done = 0;              // runs finished and written in this session
  bool interrupted = false;  // a signal stopped it
  double seconds = 0;
};

// Throws what a run throws (InputError for logs that cannot be used) after
// the other workers have finished their runs.
StudyRunnerResult RunStudyRuns(const StudySpec& spec, const std::vector<int>& pending,
                               RecordAppender* out, const StudyRunnerOptions& options);

// SIGINT and SIGTERM request a stop (see above).
void InstallStudyStopHandler();
bool StudyStopRequested();

}  // namespace coaxid
