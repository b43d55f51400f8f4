// Cost of one evaluation of the templated vehicle model
// (dynamics/vehicle_model.h): VehicleModel::Derivative with double (target:
// under 0.2 us, it runs inside every integrator step), with ceres::Jet<double,
// 8> and Jet<double, 12> (the EKF's and Ceres' Jacobians; 16, 24 and 32: the
// widths a Jacobian pass could take, dynamics/autodiff.h), and
// DerivativeJacobians with the 12 unknown base parameters; each with no effect
// (the paper's model) and with every effect of the library enabled; and
// DerivativeJacobians with every effect over 4-20 parameters (the widths of
// the Jet passes, dynamics/autodiff.h).
//
// Run: model_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>
#include <ceres/jet.h>

#include <map>
#include <string>
#include <vector>

#include "core/input_hold.h"
#include "core/parameters.h"
#include "dynamics/effects/effect_library.h"
#include "dynamics/model_jacobian.h"
#include "dynamics/state.h"
#include "dynamics/vehicle.h"
#include "dynamics/vehicle_model.h"

namespace coaxid {
namespace {

Vehicle MakeBenchVehicle(bool all_effects) {
  Vehicle v = LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
  if (all_effects) {
    for (const auto& info : EffectLibrary()) {
      if (info.num_own_states > 0) continue;  // the 12-state benchmark cases
      std::map<std::string, ParameterOverride> overrides;
      for (const auto& spec : info.parameters) overrides[spec.name].value = spec.typical;
      v = WithEffect(v, info.name, overrides);
    }
  }
  return v;
}

const Vehicle& BenchVehicle(bool all_effects) {
  static const Vehicle plain = MakeBenchVehicle(false);
  static const Vehicle full = MakeBenchVehicle(true);
  return all_effects ? full : plain;
}

// A near-hover flight state and input (moving, rotating, 1 m up).
State BenchState() {
  State x;
  x << 0.3, -0.2, -1.0, 0.4, -0.3, 0.1, 0.05, -0.04, 0.6, 0.2, -0.1, 0.05;
  return x;
}
const InputVector kBenchInput = {150.0, 164.0, 0.02, -0.015};

void BM_DerivativeDouble(benchmark::State& state) {
  const Vehicle& v = BenchVehicle(state.range(0) != 0);
  const Eigen::VectorXd theta = v.parameters.Values();
  State x = BenchState();
  State xdot;
  for (auto _ : state) {
    benchmark::DoNotOptimize(x.data());
    v.model.Derivative(theta.data(), x.data(), kBenchInput.data(), xdot.data());
    benchmark::DoNotOptimize(xdot.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_DerivativeDouble)->ArgName("all_effects")->Arg(0)->Arg(1);

// Jets with all N directions seeded (on the first N of states then
// parameters), as in DerivativeJacobians.
template <int N>
void BM_DerivativeJet(benchmark::State& state) {
  using Jet = ceres::Jet<double, N>;
  const Vehicle& v = BenchVehicle(state.range(0) != 0);
  const Eigen::VectorXd theta = v.parameters.Values();
  const State x0 = BenchState();
  std::vector<Jet> th(theta.size());
  for (int i = 0; i < theta.size(); ++i) th[i] = Jet(theta[i]);
  Jet x[kNumStates], in[kNumInputs], xdot[kNumStates];
  for (int i = 0; i < kNumStates; ++i) x[i] = i < N ? Jet(x0[i], i) : Jet(x0[i]);
  for (int k = 0; k < kNumInputs; ++k) in[k] = Jet(kBenchInput[k]);
  for (auto _ : state) {
    benchmark::DoNotOptimize(x);
    v.model.Derivative(th.data(), x, in, xdot);
    benchmark::DoNotOptimize(xdot);
    benchmark::ClobberMemory();
  }
}
BENCHMARK_TEMPLATE(BM_DerivativeJet, 8)->ArgName("all_effects")->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_DerivativeJet, 12)->ArgName("all_effects")->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_DerivativeJet, 16)->ArgName("all_effects")->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_DerivativeJet, 24)->ArgName("all_effects")->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_DerivativeJet, 32)->ArgName("all_effects")->Arg(0)->Arg(1);

// DerivativeJacobians of `v` at the bench state over theta[indices].
void TimeDerivativeJacobians(benchmark::State& state, const Vehicle& v,
                             const std::vector<int>& indices) {
  const Eigen::VectorXd theta = v.parameters.Values();
  const State x = BenchState();
  Eigen::MatrixXd dfdx, dfdp;
  for (auto _ : state) {
    const bool ok =
        DerivativeJacobians(v.model, theta, x.data(), HeldInput::Steady(kBenchInput, 0), 0, indices,
                            &dfdx, &dfdp);
    benchmark::DoNotOptimize(ok);
    benchmark::DoNotOptimize(dfdx.data());
    benchmark::DoNotOptimize(dfdp.data());
    benchmark::ClobberMemory();
  }
}

// df/dx (12 x 12) and df/dp over the 12 unknown base parameters (12 x 12).
void BM_DerivativeJacobians12Unknowns(benchmark::State& state) {
  std::vector<int> indices;
  for (int i = kAlpha; i < kNumBaseParameters; ++i) indices.push_back(i);
  TimeDerivativeJacobians(state, BenchVehicle(state.range(0) != 0), indices);
}
BENCHMARK(BM_DerivativeJacobians12Unknowns)->ArgName("all_effects")->Arg(0)->Arg(1);

// df/dx and df/dp with every effect over the first P parameters: 12 + P
// directions, so every mix of pass widths (dynamics/autodiff.h).
void BM_DerivativeJacobiansWithParameters(benchmark::State& state) {
  const Vehicle& v = BenchVehicle(true);
  std::vector<int> indices;
  for (int i = 0; i < state.range(0) && i < v.parameters.Values().size(); ++i) {
    indices.push_back(i);
  }
  TimeDerivativeJacobians(state, v, indices);
}
BENCHMARK(BM_DerivativeJacobiansWithParameters)->ArgName("P")->Arg(4)->Arg(8)->Arg(12)->Arg(16)->Arg(20);

}  // namespace
}  // namespace coaxid

BENCHMARK_MAIN();
