// `discover` on flight logs alone, as a new user would run it on a vehicle it
// was never tuned on (issue 13): a 60 s, 200 Hz closed-loop flight with
// multisines on all four inputs for estimation and a 30 s flight with 3211
// inputs held out, no balance log (d held for the scale, model.md decision
// 8), the whole library as candidates. The truth vehicle is the one of
// flight_only_bench (every unknown 10-30 % off, seed 37, hover trim
// |omega1 - omega2| = 45 rad/s), flown with a stiffer controller than the
// defaults. Arg(case):
//   0: no undeclared effect (anything added is wrong);
//   1: gyroscopic, J_r = 1e-4 kg m^2 (the library's typical strength);
//   2: ground_effect, k_ge = 1, the whole flight 0.13-0.9 m above the floor;
//   3: wind (0.8, -0.5, 0) m/s.
// Counters: seconds of the whole loop, effects added (label), whether the
// answer is right.
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "bench/ident/bench_vehicle.h"
#include "experiments/simulation/scenario.h"
#include "experiments/simulation/simulate_experiment.h"
#include "ident/discover/discovery.h"

namespace coaxid {
namespace {


struct Case {
  std::string name;
  std::vector<std::pair<std::string, std::map<std::string, ParameterOverride>>> effects;
  bool low = false;
};

ParameterOverride Value(double v) {
  ParameterOverride o;
  o.value = v;
  return o;
}

Case CaseAt(int k) {
  switch (k) {
    case 1: return {"gyroscopic", {{"gyroscopic", {{"J_r", Value(1e-4)}}}}, false};
    case 2: return {"ground_effect", {{"ground_effect", {{"k_ge", Value(1.0)}}}}, true};
    case 3:
      return {"wind", {{"wind", {{"wn", Value(0.8)}, {"we", Value(-0.5)}, {"wd", Value(0)}}}}, false};
    default: return {"none", {}, false};
  }
}

Scenario FlightFor(const Vehicle& nominal, const Case& c, bool held_out) {
  Scenario s;
  s.kind = Scenario::Kind::kFlight;
  s.name = c.name;
  s.seed = held_out ? 7007 : 4004;
  for (const auto& [name, factor] : Seed37TruthFactors()) {
    s.truth_parameters[name] = factor * nominal.parameters.Value(name);
  }
  s.truth_effects = c.effects;
  FlightScenario& f = s.flight;
  f.duration_s = held_out ? 30 : 60;
  f.rate_hz = 200;
  f.gains = StifferGains();
  const double h0 = c.low ? 0.15 : 2.0, h1 = c.low ? 0.8 : 2.3, h2 = c.low ? 0.4 : 1.7;
  f.waypoints = {{0, 0.0, 0.0, h0, 0.3}, {15, -0.4, 0.3, h1, 0.0}, {35, 0.3, -0.3, h2, -0.25},
                 {50, 0.0, 0.0, h0 + 0.1, 0.1}};
  Excitation& e = f.excitation;
  e.type = held_out ? Excitation::Type::k3211 : Excitation::Type::kMultisine;
  e.start_s = 1.0;
  e.min_hz = 0.15;
  e.max_hz = 5.0;
  e.period_s = 20.0;
  e.amplitude = {{"omega1", 5.0}, {"omega2", 5.0}, {"delta_cx", 0.06}, {"delta_cy", 0.06}};
  return s;
}

void BM_DiscoverFlightOnly(benchmark::State& state) {
  const Vehicle nominal = LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
  const Case c = CaseAt(static_cast<int>(state.range(0)));
  const Scenario estimation = FlightFor(nominal, c, false);
  const Scenario validation = FlightFor(nominal, c, true);
  const Vehicle truth = MakeTruthVehicle(nominal.config, estimation);
  const std::vector<EstimationLog> logs = {MakeEstimationLog(SimulateScenario(truth, estimation))};
  const std::vector<EstimationLog> held = {MakeEstimationLog(SimulateScenario(truth, validation))};
  DiscoveryOptions o;
  o.fit.num_threads = 2;
  o.progress = [](const std::string& l) { std::fprintf(stderr, "%s\n", l.c_str()); };
  DiscoveryResult r;
  for (auto _ : state) r = Discover(nominal, logs, held, o);
  std::string added;
  for (const std::string& e : r.added) added += (added.empty() ? "" : ",") + e;
  const bool right = c.name == "none" ? r.added.empty()
                                      : (r.added.size() == 1 && r.added.front() == c.name);
  state.counters["discover_s"] = r.seconds;
  state.counters["right"] = right;
  std::fprintf(stderr, "%s\n", DiscoveryJson(r, o)["candidates"].dump(1).c_str());
  state.SetLabel("truth: " + c.name + "; added: " + (added.empty() ? "none" : added));
}
BENCHMARK(BM_DiscoverFlightOnly)->DenseRange(0, 3)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
}  // namespace coaxid

BENCHMARK_MAIN();
