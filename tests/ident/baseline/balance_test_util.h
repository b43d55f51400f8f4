// Simulated balance logs for the linear_kf tests, from a truth that satisfies
// the linear model's assumptions (paper sect. 4): the config's Cz and d (the
// method takes them as known), parametric sigma (so that the map sigma is
// exact at the grid points the holds sit on), no effect. The other unknowns
// are off-nominal, as a real vehicle's would be.
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "core/log.h"
#include "dynamics/vehicle.h"
#include "experiments/simulation/scenario.h"
#include "experiments/simulation/simulate_experiment.h"
#include "ident/baseline/linear_baseline.h"

namespace coaxid {
namespace testing_util {

inline Vehicle ReferenceVehicle() {
  return LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
}

// The truth's unknowns (Cz and d stay at the config's 1.0 and 0.10 m).
inline std::map<std::string, double> TruthOverrides() {
  return {{"alpha", -5.9e-5},
          {"beta", -5.3e-5},
          {"sigma0", 0.12},
          {"gamma1", 1.25e-6},
          {"gamma2", -1.05e-6}};
}

inline Vehicle TruthVehicle(const std::map<std::string, double>& extra = {}) {
  Scenario scenario;
  scenario.kind = Scenario::Kind::kBalance;
  scenario.truth_parameters = TruthOverrides();
  for (const auto& [name, value] : extra) scenario.truth_parameters[name] = value;
  return MakeTruthVehicle(ReferenceVehicle().config, scenario);
}

// A balance log of the truth (the shipped scenario's grid by default).
inline Log SimulatedBalance(const BalanceScenario& s, uint64_t seed,
                            const std::map<std::string, double>& extra = {}) {
  Log log = SimulateBalance(TruthVehicle(extra), s, seed);
  log.source = "simulated.csv";
  return log;
}

inline BalanceScenario NoiseFree(BalanceScenario s) {
  for (auto& [name, std] : s.noise_std) std = 0;
  return s;
}

// The truth's Theta = (beta, Cz alpha, Cz beta, gamma1, gamma2) and alpha.
inline PsiVector TruthPsi(const Vehicle& truth) {
  const ParameterSet& p = truth.parameters;
  PsiVector psi;
  psi << p.Value("beta"), p.Value("Cz") * p.Value("alpha"), p.Value("Cz") * p.Value("beta"),
      p.Value("gamma1"), p.Value("gamma2"), p.Value("alpha");
  return psi;
}

}  // namespace testing_util
}  // namespace coaxid
