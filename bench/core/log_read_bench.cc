// Speed of reading flight logs (target: a 1,000,000-row, 20-column log well
// under one second) and of the input hold lookup every simulation step makes.
//
// Two logs are written once to the temporary folder:
//   logger: values at a sensor logger's resolution (1e-4), ~8 characters a field;
//   full:   raw doubles written with the shortest exact form, ~18 characters a
//           field, the worst case (what WriteLog produces from simulated data).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/input_hold.h"
#include "core/log.h"

namespace coaxid {
namespace {

constexpr int kRows = 1000000;
constexpr double kRateHz = 200;

std::string g_logger_path;
std::string g_full_path;

// A 200 Hz flight: t, the 4 inputs, the 12 states and the 3 accelerometer axes.
Log MakeFlightLog(bool quantize) {
  const std::vector<std::string> names = {
      "omega1", "omega2", "delta_cx", "delta_cy", "x", "y", "z",  "u",  "v", "w",
      "phi",    "theta",  "psi",      "p",        "q", "r", "ax", "ay", "az"};
  Log log;
  log.kind = LogKind::kFlight;
  log.metadata = {{"vehicle", "bench"}, {"rate_hz", "200"}};
  std::vector<double> t(kRows);
  for (int k = 0; k < kRows; ++k) t[k] = k / kRateHz;
  log.SetColumn("t", t);
  for (size_t j = 0; j < names.size(); ++j) {
    std::vector<double> column(kRows);
    const double offset = j < 2 ? 150.0 : 0.0;  // Rotor speeds hover around 150 rad/s.
    for (int k = 0; k < kRows; ++k) {
      const double v = offset + std::sin(0.37 * (j + 1) * t[k]) * (1.0 + 0.1 * j);
      column[k] = quantize ? std::round(v * 1e4) / 1e4 : v;
    }
    log.SetColumn(names[j], std::move(column));
  }
  return log;
}

std::string WriteTempLog(const char* tag, bool quantize) {
  const char* tmpdir = std::getenv("TMPDIR");
  const std::string path = std::string(tmpdir != nullptr ? tmpdir : "/tmp") + "/coaxid_bench_" +
                           tag + "_" + std::to_string(::getpid()) + ".csv";
  WriteLog(path, MakeFlightLog(quantize));
  return path;
}

void ReadLogBench(benchmark::State& state, const std::string* path) {
  const int64_t bytes = static_cast<int64_t>(ReadFile(*path).size());
  int rows = 0;
  for (auto _ : state) {
    const Log log = ReadLog(*path);
    rows = log.NumRows();
    benchmark::DoNotOptimize(log.values.data());
  }
  if (rows != kRows) state.SkipWithError("wrong row count");
  state.SetBytesProcessed(state.iterations() * bytes);
  state.counters["rows/s"] =
      benchmark::Counter(static_cast<double>(rows), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["MB"] = static_cast<double>(bytes) / 1e6;
}

void BM_ReadLog_Logger(benchmark::State& state) { ReadLogBench(state, &g_logger_path); }
void BM_ReadLog_FullPrecision(benchmark::State& state) { ReadLogBench(state, &g_full_path); }
BENCHMARK(BM_ReadLog_Logger)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_ReadLog_FullPrecision)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// The hold of a 1M-sample log (5000 s at 200 Hz).
const InputHold& BenchHold() {
  static const InputHold hold = [] {
    std::vector<double> times(kRows);
    std::vector<InputVector> inputs(kRows);
    for (int k = 0; k < kRows; ++k) {
      times[k] = k / kRateHz;
      inputs[k] = {150.0 + k % 7, 160.0, 0.001 * (k % 11), -0.001};
    }
    return InputHold(std::move(times), std::move(inputs));
  }();
  return hold;
}

// Random query times: every lookup misses the cache lines of the previous one.
void BM_InputHoldAt_Random(benchmark::State& state) {
  const InputHold& hold = BenchHold();
  std::mt19937 rng(42);  // Seeded so runs compare.
  std::uniform_real_distribution<double> query(-1.0, kRows / kRateHz + 1.0);
  std::vector<double> queries(4096);
  for (double& q : queries) q = query(rng);
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(hold.At(queries[i]));
    i = (i + 1) & (queries.size() - 1);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_InputHoldAt_Random);

// What an integrator does: times advancing by a fraction of the sample period.
void BM_InputHoldAt_Sequential(benchmark::State& state) {
  const InputHold& hold = BenchHold();
  const double step = 0.25 / kRateHz;
  const double end = kRows / kRateHz;
  double t = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(hold.At(t));
    t += step;
    if (t > end) t = 0;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_InputHoldAt_Sequential);

}  // namespace
}  // namespace coaxid

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  coaxid::g_logger_path = coaxid::WriteTempLog("logger", /*quantize=*/true);
  coaxid::g_full_path = coaxid::WriteTempLog("full", /*quantize=*/false);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  std::remove(coaxid::g_logger_path.c_str());
  std::remove(coaxid::g_full_path.c_str());
  return 0;
}
