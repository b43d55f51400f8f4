#include "experiments/studies/records.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <map>

#include "core/atomic_file.h"
#include "core/errors.h"
#include "core/report.h"

namespace coaxid {
namespace {

namespace fs = std::filesystem;

std::string Absolute(const std::string& path) {
  return fs::absolute(path).lexically_normal().string();
}

// Records of one JSONL file; a last line without its newline is torn and skipped.
void ReadRecordFile(const std::string& path, const StudySpec& spec,
                    std::map<int, nlohmann::json>* by_index) {
  const std::string text = ReadFile(path);
  size_t start = 0;
  for (int line = 1; start < text.size(); ++line) {
    const size_t end = text.find('\n', start);
    if (end == std::string::npos) break;  // torn last line
    const std::string where = path + ": line " + std::to_string(line);
    nlohmann::json r;
    try {
      r = nlohmann::json::parse(text.substr(start, end - start));
    } catch (const nlohmann::json::exception& e) {
      throw InputError(where + ": not a JSON run record (" + e.what() + ")");
    }
    start = end + 1;
    if (!r.is_object() || !r.contains("key") || !r.contains("point") || !r.contains("seed_index") ||
        !r.contains("spec_hash")) {
      throw InputError(where + ": not a run record (needs key, point, seed_index, spec_hash)");
    }
    if (r["spec_hash"] != spec.hash) {
      throw InputError(where + ": a run of another spec (hash " +
                       r["spec_hash"].get<std::string>() + ", this spec " + spec.hash + ")");
    }
    const int point = r["point"].get<int>(), seed = r["seed_index"].get<int>();
    if (point < 0 || point >= spec.sweep.NumPoints() || seed < 0 || seed >= spec.seed_count) {
      throw InputError(where + ": run " + r["key"].get<std::string>() + " is not in the spec");
    }
    (*by_index)[point * spec.seed_count + seed] = std::move(r);
  }
}

}  // namespace

void PrepareStudyFolder(const StudySpec& spec, const std::string& dir, bool restart) {
  MakeOutputFolder(dir);
  const std::string header_path = dir + "/study.json";
  if (fs::exists(header_path)) {
    const nlohmann::json old = ReadStudyHeader(dir);
    if (old.value("spec_hash", "") != spec.hash) {
      if (!restart) {
        throw InputError(dir + " holds a study of another spec (" + old.value("spec", "?") +
                         ", hash " + old.value("spec_hash", "?") + "; this spec " + spec.hash +
                         "): use another --out, or --restart to discard its runs");
      }
    }
    if (restart) {
      std::error_code ec;
      for (const char* name : {"runs.jsonl", "summary.json", "summary.md"}) {
        fs::remove(dir + "/" + name, ec);
      }
      fs::remove_all(dir + "/parts", ec);
      fs::remove_all(dir + "/plots", ec);
    }
  }
  nlohmann::json points = nlohmann::json::array();
  for (int p = 0; p < spec.sweep.NumPoints(); ++p) points.push_back(spec.sweep.Label(p));
  WriteJson(header_path, {{"study", spec.name},
                          {"spec", Absolute(spec.source)},
                          {"spec_hash", spec.hash},
                          {"setting", SweepSettingName(spec.sweep.setting)},
                          {"points", points},
                          {"seeds", spec.seed_count},
                          {"base_seed", spec.base_seed},
                          {"runs", spec.NumRuns()}});
}

nlohmann::json ReadStudyHeader(const std::string& dir) {
  const std::string path = dir + "/study.json";
  if (!fs::exists(path)) throw InputError(dir + ": no study here (no study.json)");
  try {
    return nlohmann::json::parse(ReadFile(path));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": not JSON (" + e.what() + ")");
  }
}

std::vector<nlohmann::json> ReadStudyRecords(const StudySpec& spec, const std::string& dir) {
  std::map<int, nlohmann::json> by_index;
  std::vector<std::string> files;
  if (fs::exists(dir + "/runs.jsonl")) files.push_back(dir + "/runs.jsonl");
  std::error_code ec;
  if (fs::is_directory(dir + "/parts", ec)) {
    std::vector<std::string> parts;
    for (const auto& entry : fs::directory_iterator(dir + "/parts")) {
      if (entry.path().extension() == ".jsonl") parts.push_back(entry.path().string());
    }
    std::sort(parts.begin(), parts.end());
    files.insert(files.end(), parts.begin(), parts.end());
  }
  for (const std::string& f : files) ReadRecordFile(f, spec, &by_index);
  std::vector<nlohmann::json> out;
  for (auto& [index, record] : by_index) out.push_back(std::move(record));
  return out;
}

std::set<std::string> RecordKeys(const std::vector<nlohmann::json>& records) {
  std::set<std::string> keys;
  for (const auto& r : records) keys.insert(r["key"].get<std::string>());
  return keys;
}

RecordAppender::RecordAppender(const std::string& path) : path_(path) {
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd_ < 0) throw InputError("cannot open " + path + ": " + std::strerror(errno));
  // Drop a torn last line, so the next record starts on a line of its own.
  const std::string text = ReadFile(path);
  if (!text.empty() && text.back() != '\n') {
    const size_t keep = text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1;
    if (::ftruncate(fd_, static_cast<off_t>(keep)) != 0) {
      throw InputError("cannot truncate the torn last line of " + path);
    }
  }
}

RecordAppender::~RecordAppender() {
  if (fd_ >= 0) ::close(fd_);
}

void RecordAppender::Append(const nlohmann::json& record) {
  const std::string line = record.dump() + "\n";
  std::lock_guard<std::mutex> lock(mutex_);
  // O_APPEND and a single write: the line lands whole at the end.
  const ssize_t n = ::write(fd_, line.data(), line.size());
  if (n != static_cast<ssize_t>(line.size()) || ::fsync(fd_) != 0) {
    throw InputError("cannot append to " + path_ + ": " + std::strerror(errno));
  }
}

}  // namespace coaxid
