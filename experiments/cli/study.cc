#include "experiments/cli/study.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include <gflags/gflags.h>

#include "core/atomic_file.h"
#include "core/cores.h"
#include "core/errors.h"
#include "core/plot.h"
#include "core/report.h"
#include "core/yaml_util.h"
#include "experiments/cli/flag_checks.h"
#include "experiments/cli/flags.h"
#include "experiments/studies/mpi.h"
#include "experiments/studies/plots.h"
#include "experiments/studies/records.h"
#include "experiments/studies/run.h"
#include "experiments/studies/runner.h"
#include "experiments/studies/summary.h"

DEFINE_string(spec, "", "study: the study spec (YAML, docs/study.md)");
DEFINE_int32(jobs, 0, "study: worker threads (0: every core; under mpirun: 1 per rank)");
DEFINE_bool(restart, false, "study: discard the runs of another spec in --out and start over");
DEFINE_int64(max_runs, -1, "study: stop after this many runs (resume later; < 0: all)");
DEFINE_int32(export, 0,
             "study: write this many independent jobs (job spec + shell script) to --out/jobs/ "
             "instead of running");
DEFINE_bool(merge, false, "study: merge --out's runs and parts and write the summary");
DEFINE_string(job, "", "study: run one exported job (--out/jobs/job_K.yaml)");
DEFINE_string(run, "",
              "study: look into one run (its key, e.g. p0_s12): write its simulated logs and "
              "its record to --out, the methods' progress on stderr; the study folder is untouched");
DEFINE_bool(logs_only, false,
            "study: with --run, only simulate and write the run's logs (and its draw in run.json); "
            "run no method");

namespace coaxid {
namespace {

namespace fs = std::filesystem;

constexpr const char* kStudyUsage =
    "usage: coaxid study --spec=FILE --out=DIR [--jobs=N] [--restart] [--max_runs=N]\n"
    "       coaxid study --spec=FILE --out=DIR --export=N\n"
    "       coaxid study --job=DIR/jobs/job_K.yaml [--jobs=N]\n"
    "       coaxid study --merge --out=DIR\n"
    "       coaxid study --spec=FILE --run=KEY --out=DIR [--logs_only]";

std::string Absolute(const std::string& path) {
  return fs::absolute(path).lexically_normal().string();
}

int Jobs(int default_jobs) {
  if (FLAGS_jobs < 0) throw InputError("--jobs must be >= 0 (0: every core)");
  return FLAGS_jobs > 0 ? FLAGS_jobs : default_jobs;
}

// Summary, markdown and plots from every record in DIR.
void WriteStudySummary(const StudySpec& spec, const std::string& dir) {
  const std::vector<nlohmann::json> records = ReadStudyRecords(spec, dir);
  nlohmann::json summary = SummarizeStudy(spec, records);
  std::error_code ec;
  fs::create_directories(dir + "/plots", ec);
  std::string plot_error;
  const std::vector<std::string> plots =
      RenderFigures(StudyFigures(spec, summary, records), dir + "/plots", &plot_error);
  std::string markdown = StudySummaryMarkdown(summary);
  if (!plots.empty()) {
    markdown += "\n## Plots\n\n";
    for (const std::string& p : plots) markdown += "![" + p + "](plots/" + p + ")\n";
  }
  if (!plot_error.empty()) markdown += "\nSome plots were skipped: " + plot_error + "\n";
  WriteJson(dir + "/summary.json", summary);
  WriteFileAtomically(dir + "/summary.md", markdown);
  std::fprintf(stderr, "study: %zu of %d runs summarised -> %s/summary.md\n", records.size(),
               spec.NumRuns(), dir.c_str());
}

// runs.jsonl holds every record of the folder, in run order.
void MergeRecords(const StudySpec& spec, const std::string& dir) {
  const std::vector<nlohmann::json> records = ReadStudyRecords(spec, dir);
  std::string text;
  for (const nlohmann::json& r : records) text += r.dump() + "\n";
  WriteFileAtomically(dir + "/runs.jsonl", text);
  const std::set<std::string> done = RecordKeys(records);
  const std::vector<int> missing = PendingRuns(spec, done);
  if (!missing.empty()) {
    std::string keys;
    for (size_t k = 0; k < missing.size() && k < 10; ++k) {
      const StudyRunId id = RunIdAt(spec, missing[k]);
      keys += (k ? ", " : "") + RunKey(id.point, id.seed_index);
    }
    std::fprintf(stderr, "study: merged %zu of %d runs; %zu missing (%s%s)\n", records.size(),
                 spec.NumRuns(), missing.size(), keys.c_str(), missing.size() > 10 ? ", ..." : "");
  } else {
    std::fprintf(stderr, "study: merged all %zu runs -> %s/runs.jsonl\n", records.size(),
                 dir.c_str());
  }
}

// The spec a folder's study.json names, checked against the hash it recorded.
StudySpec SpecOfFolder(const std::string& dir) {
  const nlohmann::json header = ReadStudyHeader(dir);
  const StudySpec spec = LoadStudySpec(header.at("spec").get<std::string>());
  if (spec.hash != header.at("spec_hash").get<std::string>()) {
    throw InputError(spec.source + " (or a file it names) changed since " + dir +
                     " was started (hash " + header["spec_hash"].get<std::string>() + ", now " +
                     spec.hash + ")");
  }
  return spec;
}

// Runs the pending runs of one shard into `records_path`. Returns whether it
// was interrupted.
bool RunShard(const StudySpec& spec, const std::string& dir, const std::string& records_path,
              int shard, int shards, int jobs, const std::string& label) {
  const std::set<std::string> done = RecordKeys(ReadStudyRecords(spec, dir));
  const std::vector<int> pending = PendingRuns(spec, done, shard, shards);
  const int shard_total = static_cast<int>(PendingRuns(spec, {}, shard, shards).size());
  std::fprintf(stderr, "%s: %s, %d runs (%d point(s) x %d seeds)%s, %zu to do, %d thread(s)\n",
               label.c_str(), spec.name.c_str(), shard_total, spec.sweep.NumPoints(),
               spec.seed_count, shards > 1 ? " in this shard" : "", pending.size(), jobs);
  RecordAppender appender(records_path);
  StudyRunnerOptions options;
  options.jobs = jobs;
  options.max_runs = FLAGS_max_runs;
  options.label = label;
  options.done_before = shard_total - static_cast<int>(pending.size());
  options.total = shard_total;
  const StudyRunnerResult r = RunStudyRuns(spec, pending, &appender, options);
  std::fprintf(stderr, "%s: %d runs in %.1f s%s\n", label.c_str(), r.done, r.seconds,
               r.interrupted ? " (interrupted: rerun the same command to resume)" : "");
  return r.interrupted;
}

int Merge() {
  RequireFlag(FLAGS_out, "out", kStudyUsage);
  const StudySpec spec = SpecOfFolder(FLAGS_out);
  MergeRecords(spec, FLAGS_out);
  WriteStudySummary(spec, FLAGS_out);
  return 0;
}

std::string JobYaml(const StudySpec& spec, const std::string& dir, int shard, int shards) {
  YAML::Emitter y;
  y << YAML::BeginMap << YAML::Key << "spec" << YAML::Value << Absolute(spec.source) << YAML::Key
    << "spec_hash" << YAML::Value << spec.hash << YAML::Key << "out" << YAML::Value << Absolute(dir)
    << YAML::Key << "shard" << YAML::Value << shard << YAML::Key << "shards" << YAML::Value
    << shards << YAML::Key << "runs" << YAML::Value
    << static_cast<int>(PendingRuns(spec, {}, shard, shards).size()) << YAML::EndMap;
  return std::string("# coaxid study job ") + std::to_string(shard) + " of " +
         std::to_string(shards) + ": runs i with i mod " + std::to_string(shards) + " = " +
         std::to_string(shard) + " (docs/study.md)\n" + y.c_str() + "\n";
}

int Export() {
  const StudySpec spec = LoadStudySpec(FLAGS_spec);
  if (FLAGS_export > spec.NumRuns()) {
    throw InputError("--export=" + std::to_string(FLAGS_export) + ": the study has only " +
                     std::to_string(spec.NumRuns()) + " runs");
  }
  PrepareStudyFolder(spec, FLAGS_out, FLAGS_restart);
  const std::string jobs = FLAGS_out + "/jobs";
  std::error_code ec;
  fs::create_directories(jobs, ec);
  if (ec) throw InputError("cannot create " + jobs + ": " + ec.message());
  const std::string binary = fs::read_symlink("/proc/self/exe", ec).string();
  for (int k = 0; k < FLAGS_export; ++k) {
    const std::string stem = jobs + "/job_" + std::to_string(k);
    WriteFileAtomically(stem + ".yaml", JobYaml(spec, FLAGS_out, k, FLAGS_export));
    const std::string script =
        "#!/bin/sh\n"
        "# coaxid study " +
        spec.name + ", job " + std::to_string(k) + " of " + std::to_string(FLAGS_export) +
        ": appends to " + Absolute(FLAGS_out) + "/parts/job_" + std::to_string(k) +
        ".jsonl; resubmitting resumes it.\n"
        "# Submit with sbatch, qsub, or run it; then `coaxid study --merge --out=" +
        Absolute(FLAGS_out) +
        "`.\n"
        "#SBATCH --job-name=coaxid-study-" +
        std::to_string(k) +
        "\n"
        "#SBATCH --ntasks=1\n"
        "#PBS -N coaxid-study-" +
        std::to_string(k) +
        "\n"
        "exec \"" +
        binary + "\" study --job=\"" + Absolute(stem + ".yaml") + "\" --jobs=${COAXID_JOBS:-0}\n";
    WriteFileAtomically(stem + ".sh", script);
    fs::permissions(stem + ".sh", fs::perms::owner_exec | fs::perms::group_exec,
                    fs::perm_options::add, ec);
  }
  std::fprintf(stderr, "study: %d runs exported as %d jobs -> %s/job_*.sh\n", spec.NumRuns(),
               FLAGS_export, jobs.c_str());
  return 0;
}

int Job() {
  const std::string where = FLAGS_job;
  const YAML::Node node = ParseYaml(ReadFile(where), where);
  CheckKeys(node, {"spec", "spec_hash", "out", "shard", "shards", "runs"}, where);
  for (const char* key : {"spec", "spec_hash", "out", "shard", "shards"}) {
    if (!node[key]) throw InputError(where + ": missing '" + key + "'");
  }
  const std::string out = ReadString(node["out"], where + ": out");
  const int shard = ReadInt(node["shard"], where + ": shard");
  const int shards = ReadInt(node["shards"], where + ": shards");
  if (!(shards >= 1 && shard >= 0 && shard < shards)) {
    throw InputError(where + ": need 0 <= shard < shards");
  }
  const StudySpec spec = LoadStudySpec(ReadString(node["spec"], where + ": spec"));
  if (spec.hash != ReadString(node["spec_hash"], where + ": spec_hash")) {
    throw InputError(where + ": " + spec.source +
                     " (or a file it names) changed since the "
                     "export; export again");
  }
  ReadStudyHeader(out);
  std::error_code ec;
  fs::create_directories(out + "/parts", ec);
  InstallStudyStopHandler();
  const bool interrupted =
      RunShard(spec, out, out + "/parts/job_" + std::to_string(shard) + ".jsonl", shard, shards,
               Jobs(NumCores()),
               "study job " + std::to_string(shard));
  return interrupted ? 130 : 0;
}

int RunWithMpi(const MpiWorld& world) {
  // Rank 0 checks the folder; every rank learns whether it may go on.
  int status = 0;
  StudySpec spec;
  try {
    spec = LoadStudySpec(FLAGS_spec);
    if (world.rank == 0) {
      PrepareStudyFolder(spec, FLAGS_out, FLAGS_restart);
      std::error_code ec;
      fs::create_directories(FLAGS_out + "/parts", ec);
    }
  } catch (const InputError& e) {
    if (world.rank == 0) std::fprintf(stderr, "coaxid study: %s\n", e.what());
    status = 2;
  }
  if (MpiMax(world, status) != 0) return 2;
  InstallStudyStopHandler();
  bool interrupted = false;
  try {
    interrupted = RunShard(
        spec, FLAGS_out, FLAGS_out + "/parts/rank_" + std::to_string(world.rank) + ".jsonl",
        world.rank, world.size, Jobs(1),
        "study rank " + std::to_string(world.rank) + "/" + std::to_string(world.size));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "coaxid study (rank %d): %s\n", world.rank, e.what());
    status = 1;
  }
  // Collectives before rank 0's merge, so that no rank waits on one that failed.
  status = MpiMax(world, status);
  interrupted = MpiMax(world, interrupted ? 1 : 0) != 0;
  if (status == 0 && world.rank == 0) {
    MergeRecords(spec, FLAGS_out);
    WriteStudySummary(spec, FLAGS_out);
  }
  return status != 0 ? status : interrupted ? 130 : 0;
}

// --run=KEY: one run, its logs and record into --out, progress on stderr.
int OneRun() {
  const StudySpec spec = LoadStudySpec(FLAGS_spec);
  int index = -1;
  for (int i = 0; i < spec.NumRuns(); ++i) {
    const StudyRunId id = RunIdAt(spec, i);
    if (RunKey(id.point, id.seed_index) == FLAGS_run) index = i;
  }
  if (index < 0) {
    throw InputError("--run: '" + FLAGS_run + "' is not a run of " + FLAGS_spec + " (keys p0_s0 .. " +
                     RunKey(spec.sweep.NumPoints() - 1, spec.seed_count - 1) + ")");
  }
  fs::create_directories(FLAGS_out);
  StudyRunDetail detail;
  detail.logs_dir = FLAGS_out;
  detail.logs_only = FLAGS_logs_only;
  detail.progress = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const nlohmann::json record = RunStudyRun(spec, RunIdAt(spec, index), detail);
  WriteJson(FLAGS_out + "/run.json", record);
  std::fprintf(stderr, "study: run %s -> %s/run.json\n", FLAGS_run.c_str(), FLAGS_out.c_str());
  return 0;
}

}  // namespace

int RunStudy() {
  if (FLAGS_merge) return Merge();
  if (!FLAGS_job.empty()) return Job();
  RequireFlag(FLAGS_spec, "spec", kStudyUsage);
  RequireFlag(FLAGS_out, "out", kStudyUsage);
  if (FLAGS_export < 0) throw InputError("--export must be a number of jobs >= 1");
  if (FLAGS_export > 0) return Export();
  if (FLAGS_logs_only && FLAGS_run.empty()) throw InputError("--logs_only needs --run=KEY");
  if (!FLAGS_run.empty()) return OneRun();
  const MpiWorld world = StartMpiIfLaunched();
  if (world.active) {
    int status = 0;
    try {
      status = RunWithMpi(world);
    } catch (...) {
      FinishMpi(world);
      throw;
    }
    FinishMpi(world);
    return status;
  }
  const StudySpec spec = LoadStudySpec(FLAGS_spec);
  const int jobs = Jobs(NumCores());
  PrepareStudyFolder(spec, FLAGS_out, FLAGS_restart);
  InstallStudyStopHandler();
  const bool interrupted =
      RunShard(spec, FLAGS_out, FLAGS_out + "/runs.jsonl", 0, 1, jobs, "study");
  WriteStudySummary(spec, FLAGS_out);
  return interrupted ? 130 : 0;
}

}  // namespace coaxid
