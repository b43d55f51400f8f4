// A 60 s closed-loop flight simulation at 200 Hz control and logging (12,000
// input changes, one CVODE restart each), sensors and log included: the cost
// of producing one flight log (issue target: under 50 ms). Also the
// open-loop replay of 1 s of logged inputs with and without CVODES
// sensitivities (what one output-error segment costs).
#include <cmath>

#include <benchmark/benchmark.h>

#include "dynamics/simulator.h"
#include "dynamics/trim.h"
#include "experiments/simulation/simulate_experiment.h"

namespace coaxid {
namespace {

const Vehicle& Reference() {
  static const Vehicle v = LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
  return v;
}

void BM_ClosedLoopFlight60s(benchmark::State& state) {
  FlightScenario scenario;
  scenario.duration_s = 60;
  IntegratorOptions options;
  // 0: Adams + fixed point, 1: BDF + Newton, 2: explicit Runge-Kutta (Dormand-Prince 5(4)).
  const IntegratorOptions::Method methods[3] = {IntegratorOptions::Method::kAdams,
                                                IntegratorOptions::Method::kBdf,
                                                IntegratorOptions::Method::kExplicitRungeKutta};
  options.method = methods[state.range(0)];
  options.newton = state.range(0) == 1;
  options.relative_tolerance = std::pow(10.0, -static_cast<double>(state.range(1)));
  options.absolute_tolerance = options.relative_tolerance * 1e-2;
  for (auto _ : state) {
    Log log = SimulateFlight(Reference(), scenario, 1, options);
    benchmark::DoNotOptimize(log.values.data());
  }
  const char* names[3] = {"Adams+fixed-point", "BDF+Newton", "explicit RK 5(4)"};
  state.SetLabel(std::string(names[state.range(0)]) +
                 ", rtol 1e-" + std::to_string(state.range(1)));
}
BENCHMARK(BM_ClosedLoopFlight60s)
    ->Args({0, 7})
    ->Args({0, 6})
    ->Args({0, 5})
    ->Args({1, 7})
    ->Args({2, 7})
    ->Args({2, 6})
    ->Unit(benchmark::kMillisecond);

void BM_ReplayOneSecond(benchmark::State& state) {
  FlightScenario scenario;
  scenario.duration_s = 3;
  static const Log log = SimulateFlight(Reference(), scenario, 1);
  const InputHold inputs = InputHold::FromLog(log);
  const Eigen::VectorXd theta = Reference().parameters.Values();
  const Eigen::VectorXd x0 = TrimHover(Reference().model, theta, 1.5).state;
  const bool sens = state.range(0) != 0;
  std::vector<int> unknowns;
  for (int i = kAlpha; i < kNumBaseParameters; ++i) unknowns.push_back(i);
  IntegratorOptions options;
  if (state.range(3)) options.method = IntegratorOptions::Method::kExplicitRungeKutta;
  options.sensitivity_error_control = state.range(1) != 0;
  options.relative_tolerance = 1e-6;
  options.absolute_tolerance = 1e-8;
  // range(2): 0 CVODES, 1 variational equations, 2 one RK4 step per hold.
  const SensitivityMethod method = state.range(2) == 2   ? SensitivityMethod::kRungeKuttaPerHold
                                   : state.range(2) == 1 ? SensitivityMethod::kVariationalEquations
                                                         : SensitivityMethod::kCvodes;
  Simulator simulator(Reference().model, theta, options, {sens, sens},
                      sens ? unknowns : std::vector<int>{}, method);
  Trajectory trajectory;
  for (auto _ : state) {
    if (!simulator.Run(inputs, 200, 400, x0, &trajectory)) state.SkipWithError("replay failed");
    benchmark::DoNotOptimize(trajectory.states.data());
  }
  state.SetLabel(std::string(sens ? "with sensitivities (12 x0 + 12 parameters)" : "states only") +
                 (state.range(1) ? ", sensitivities in the error test" : "") +
                 (sens ? (state.range(2) == 2   ? ", one RK4 step per hold"
                          : state.range(2) == 1 ? ", variational equations"
                                                : ", CVODES")
                       : "") +
                 (state.range(3) ? ", explicit RK 5(4)" : ", Adams") +
                 ", rtol 1e-6");
}
BENCHMARK(BM_ReplayOneSecond)
    ->Args({0, 0, 0, 0})
    ->Args({1, 1, 0, 0})
    ->Args({1, 0, 0, 0})
    ->Args({1, 1, 1, 0})
    ->Args({1, 0, 1, 0})
    ->Args({0, 0, 0, 1})
    ->Args({1, 0, 1, 1})
    ->Args({1, 0, 2, 1})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace coaxid

BENCHMARK_MAIN();
