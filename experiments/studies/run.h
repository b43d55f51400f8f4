// One run of a study (experiments/studies/spec.h): simulate the point's
// scenarios with the run's seed, run every method of the spec on the logs,
// and record per parameter the estimate, the reported std and the truth.
// A pure function of (spec, point, seed): each method runs single-threaded
// and nothing depends on the time, the thread or what ran before, so the
// record is the same on any worker, process or machine.
#pragma once

#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "experiments/studies/spec.h"

namespace coaxid {

// The run's record, one line of runs.jsonl:
//   {"key": "p0_s3", "point": 0, "point_label": "0.5", "seed_index": 3, "seed": 1003,
//    "simulation": "ok" | the error,
//    "methods": {"output_error": {"ok": true, "parameters": {"alpha":
//                {"estimate": .., "std": .. | null (not identifiable), "truth": .. | null}}},
//                "discover": {"ok": true, "added": [...], "parameters": {...}},
//                "linear_kf": {"ok": false, "error": "..."}}}
// A method that fails (ComputationError, or data it cannot use) is recorded
// as failed with its message: a failure rate is a study result too.
// Looking into one run (`coaxid study --run=KEY`): the simulated logs
// written to logs_dir (held-out ones as held_out_*.csv) and the methods'
// progress lines. Neither changes the record.
struct StudyRunDetail {
  std::string logs_dir;                                // empty: no logs written
  std::function<void(const std::string&)> progress;  // nullptr: silent
  bool logs_only = false;                            // simulate and write the logs, run no method
};

nlohmann::json RunStudyRun(const StudySpec& spec, const StudyRunId& id,
                           const StudyRunDetail& detail = {});

}  // namespace coaxid
