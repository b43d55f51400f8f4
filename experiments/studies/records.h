// A study's folder (docs/study.md):
//   DIR/study.json        what study the folder holds (spec, its hash, the run count)
//   DIR/runs.jsonl        one JSON line per finished run, appended as runs finish
//   DIR/parts/*.jsonl     the same, one file per exported job or MPI rank
//   DIR/summary.json, DIR/summary.md, DIR/plots/   (experiments/studies/summary.h)
// Lines are written whole with one write() and fsync'ed, so an interrupted
// study loses at most the runs in flight; a torn last line (power loss) is
// dropped when the file is read or appended to again.
#pragma once

#include <mutex>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "experiments/studies/spec.h"

namespace coaxid {

// Creates DIR and writes DIR/study.json for the spec. If DIR already holds a
// study with another spec hash, throws InputError unless `restart`, which
// removes the old runs, parts and summary first.
void PrepareStudyFolder(const StudySpec& spec, const std::string& dir, bool restart);

// DIR/study.json, or InputError saying DIR holds no study.
nlohmann::json ReadStudyHeader(const std::string& dir);

// Every finished run of the folder (runs.jsonl and parts/*.jsonl), one per
// key, ordered by run index. Throws InputError naming the file and line for a
// line that is not a run record or belongs to another spec hash.
std::vector<nlohmann::json> ReadStudyRecords(const StudySpec& spec, const std::string& dir);
std::set<std::string> RecordKeys(const std::vector<nlohmann::json>& records);

// Appends records to a JSONL file, one whole line per write, fsync'ed.
// Thread-safe.
class RecordAppender {
 public:
  explicit RecordAppender(const std::string& path);  // InputError if it cannot open
  ~RecordAppender();
  RecordAppender(const RecordAppender&) = delete;
  RecordAppender& operator=(const RecordAppender&) = delete;
  void Append(const nlohmann::json& record);  // InputError if the write fails

 private:
  std::string path_;
  int fd_ = -1;
  std::mutex mutex_;
};

}  // namespace coaxid
