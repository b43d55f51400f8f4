// Speed of the paper's linear Kalman baseline (issue 3; target: the whole
// baseline on a 100,000-sample balance log in under 100 ms):
//   BM_WholeBaseline            holds, thrust map, sigma map, R, excitation
//                               check (Lemma 1 and eq. 73), Kalman filter with
//                               the map's uncertainty propagated, Cz, X/Y
//                               diagnostic, reconstruction and fit, from the
//                               log in memory (as `identify` runs it)
//   BM_WholeBaselineWithHoldout the same with the final 20 % held out and validated
//   BM_Holds, BM_KalmanFilter, BM_BatchLeastSquares: the parts.
// The log: the shipped balance experiment's grid (112 holds) at 100 Hz with
// 8.93 s holds, 100,016 rows, the shipped noise level.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "dynamics/vehicle.h"
#include "experiments/simulation/simulate_experiment.h"
#include "ident/baseline/linear_baseline.h"

namespace coaxid {
namespace {

const Vehicle& ReferenceVehicle() {
  static const Vehicle vehicle =
      LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
  return vehicle;
}

const Log& BenchLog() {
  static const Log log = [] {
    Scenario scenario;
    scenario.kind = Scenario::Kind::kBalance;
    scenario.truth_parameters = {{"alpha", -5.9e-5},
                                 {"beta", -5.3e-5},
                                 {"sigma0", 0.12},
                                 {"gamma1", 1.25e-6},
                                 {"gamma2", -1.05e-6}};
    BalanceScenario s;
    s.hold_s = 8.93;
    Log out = SimulateBalance(MakeTruthVehicle(ReferenceVehicle().config, scenario), s, 17);
    out.source = "bench.csv";
    return out;
  }();
  return log;
}

void BM_WholeBaseline(benchmark::State& state) {
  const Log& log = BenchLog();
  for (auto _ : state) {
    const std::vector<BalanceData> estimation = {MakeBalanceData(log)};
    const LinearBaselineResult r = RunLinearBaseline(ReferenceVehicle().parameters, estimation, {});
    benchmark::DoNotOptimize(r.estimate);
  }
  state.counters["rows"] = log.NumRows();
}
BENCHMARK(BM_WholeBaseline)->Unit(benchmark::kMillisecond);

void BM_WholeBaselineWithHoldout(benchmark::State& state) {
  const Log& log = BenchLog();
  for (auto _ : state) {
    const int cut = HoldoutStartRow(log, 0.2);
    const std::vector<BalanceData> estimation = {MakeBalanceData(log, 0, cut)};
    const std::vector<BalanceData> validation = {MakeBalanceData(log, cut)};
    const LinearBaselineResult r =
        RunLinearBaseline(ReferenceVehicle().parameters, estimation, validation);
    benchmark::DoNotOptimize(r.estimate);
  }
  state.counters["rows"] = log.NumRows();
}
BENCHMARK(BM_WholeBaselineWithHoldout)->Unit(benchmark::kMillisecond);

void BM_Holds(benchmark::State& state) {
  const Log& log = BenchLog();
  for (auto _ : state) {
    const BalanceData data = MakeBalanceData(log);
    benchmark::DoNotOptimize(data.holds.data());
  }
}
BENCHMARK(BM_Holds)->Unit(benchmark::kMillisecond);

// The filter and the batch route alone, on the model the baseline builds.
struct Prepared {
  std::vector<BalanceData> data;
  LinearBaselineResult result;
  std::vector<WeightedBalanceData> weighted;
};

const Prepared& Prepare() {
  static const Prepared p = [] {
    Prepared out;
    out.data = {MakeBalanceData(BenchLog())};
    out.result = RunLinearBaseline(ReferenceVehicle().parameters, out.data, {});
    out.weighted = {{&out.data[0], out.result.noise[0].Variances()}};
    return out;
  }();
  return p;
}

void BM_KalmanFilter(benchmark::State& state) {
  const Prepared& p = Prepare();
  for (auto _ : state) {
    const LinearKfSummary kf = RunLinearKf(p.result.model, p.weighted, p.result.kf_options);
    benchmark::DoNotOptimize(kf.estimate);
  }
}
BENCHMARK(BM_KalmanFilter)->Unit(benchmark::kMillisecond);

void BM_BatchLeastSquares(benchmark::State& state) {
  const Prepared& p = Prepare();
  for (auto _ : state) {
    const BatchLeastSquaresSummary ls =
        SolveBatchLeastSquares(p.result.model, p.weighted, p.result.kf_options);
    benchmark::DoNotOptimize(ls.estimate);
  }
}
BENCHMARK(BM_BatchLeastSquares)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace coaxid

BENCHMARK_MAIN();
