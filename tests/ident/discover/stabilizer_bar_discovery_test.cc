// The closing loop on a small coaxial helicopter with a stabilizer bar
// (issue 17): CoaX flights (configs/scenarios/coax_flight.yaml, 44 s at
// 150 Hz, flight log alone, d held) whose truth carries a bar the declared
// configs/coax.yaml lacks, with T_b, k_b and d_u drawn at random over the
// issue's ranges (T_b 0.5-2 s, k_b 0.3-1, d_u 0.1-0.2 m; draws of a fixed
// generator seed, chosen once and not tuned): discover adds stabilizer_bar
// and only it, and returns its parameters within 3 std of the truth where
// the log determines them (T_b always; k_b and d_u of a weak bar may move
// with alpha and sigma0, which a flight log alone does not separate, and the
// report then names them in a null direction). The same flight without a
// bar: nothing added.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "experiments/simulation/scenario.h"
#include "experiments/simulation/simulate_experiment.h"
#include "ident/discover/discovery.h"

namespace coaxid {
namespace {

const std::string kSource = COAXID_SOURCE_DIR;

DiscoveryOptions Options() {
  DiscoveryOptions o;
  o.alpha = 0.01;
  o.fit.num_threads = 2;
  o.fit.noise_relaxations = 1;
  if (getenv("COAXID_TEST_PROGRESS")) {
    o.progress = [](const std::string& l) { fprintf(stderr, "%s\n", l.c_str()); };
    o.fit.progress = o.progress;
  }
  return o;
}

struct BarRun {
  std::map<std::string, double> truth;  // the bar's parameters (empty: no bar)
  DiscoveryResult result;
};

BarRun DiscoverOnCoaxFlight(const std::map<std::string, double>& bar, uint64_t seed) {
  const Vehicle declared = LoadVehicle(kSource + "/configs/coax.yaml");
  Scenario scenario = LoadScenario(kSource + "/configs/scenarios/coax_flight.yaml");
  scenario.truth_effects.clear();
  if (!bar.empty()) {
    std::map<std::string, ParameterOverride> overrides;
    for (const auto& [name, value] : bar) overrides[name].value = value;
    scenario.truth_effects.emplace_back("stabilizer_bar", overrides);
  }
  const Vehicle truth = MakeTruthVehicle(declared.config, scenario);
  scenario.seed = seed;
  const Log estimation = SimulateScenario(truth, scenario);
  scenario.seed = seed + 500;
  scenario.flight.duration_s = 30;
  const Log validation = SimulateScenario(truth, scenario);
  BarRun run;
  run.truth = bar;
  run.result = Discover(declared, {MakeEstimationLog(estimation)},
                        {MakeEstimationLog(validation)}, Options());
  return run;
}

TEST(DiscoverStabilizerBar, FoundAloneWithItsParametersOnRandomBars) {
  std::mt19937_64 rng(1717);
  std::uniform_real_distribution<double> T_b(0.5, 2.0), k_b(0.3, 1.0), d_u(0.1, 0.2);
  for (int draw = 0; draw < 2; ++draw) {
    const std::map<std::string, double> bar = {{"T_b", T_b(rng)}, {"k_b", k_b(rng)},
                                               {"d_u", d_u(rng)}};
    const BarRun run = DiscoverOnCoaxFlight(bar, 3100 + draw);
    const std::string what = "draw " + std::to_string(draw) + ": T_b " +
                             std::to_string(bar.at("T_b")) + ", k_b " +
                             std::to_string(bar.at("k_b")) + ", d_u " +
                             std::to_string(bar.at("d_u"));
    ASSERT_EQ(run.result.added, std::vector<std::string>{"stabilizer_bar"}) << what;
    const ParameterSet& p = run.result.final.result.parameters;
    const IdentifiabilityReport& id = run.result.final.result.identifiability;
    for (const auto& [name, value] : bar) {
      const std::string full = "stabilizer_bar." + name;
      int k = -1;
      for (size_t i = 0; i < id.names.size(); ++i) {
        if (id.names[i] == full) k = static_cast<int>(i);
      }
      ASSERT_GE(k, 0) << what << ": " << full << " not estimated";
      std::printf("%s: %s = %.4g +- %.2g (truth %.4g)%s\n", what.c_str(), full.c_str(),
                  p.Value(full), id.std[k], value, id.identifiable[k] ? "" : " undetermined");
      if (!id.identifiable[k]) {
        // Flight logs alone do not separate alpha from sigma0 (the upper
        // rotor's thrust); a weak bar's force part does not show either, and
        // then d_u (its moment arm on that thrust) moves with them: the
        // report must say so, naming it in a null direction (measured, draw
        // 0: T_b 0.65 s, k_b 0.31; with a balance log it would be fixed).
        bool explained = false;
        for (const NullDirection& d : id.null_directions) {
          explained |= std::find(d.parameters.begin(), d.parameters.end(), full) !=
                        d.parameters.end();
        }
        EXPECT_TRUE(explained) << what << ": " << full << " undetermined without a reason";
        EXPECT_NE(name, "T_b") << what << ": the bar's time constant must be determined";
        continue;
      }
      EXPECT_LT(std::fabs(p.Value(full) - value), 3 * id.std[k])
          << what << ": " << full << " = " << p.Value(full) << " +- " << id.std[k];
    }
  }
}

TEST(DiscoverStabilizerBar, NothingAddedWithoutABar) {
  const BarRun run = DiscoverOnCoaxFlight({}, 3200);
  EXPECT_TRUE(run.result.added.empty())
      << "added " << (run.result.added.empty() ? "" : run.result.added.front());
}

}  // namespace
}  // namespace coaxid
