// Shared pieces of the closing-loop tests (discovery_test.cc on balance logs,
// discovery_flight_test.cc on flight logs): the nominal (declared) vehicle, a
// truth with chosen effects, and the 3-std check of an added parameter.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "experiments/simulation/scenario.h"
#include "experiments/simulation/simulate_experiment.h"
#include "ident/discover/discovery.h"

namespace coaxid {

using Effects = std::vector<std::pair<std::string, std::map<std::string, ParameterOverride>>>;

inline Vehicle Nominal() {
  return LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
}

inline Scenario ShippedFlightScenario() {
  return LoadScenario(std::string(COAXID_SOURCE_DIR) + "/configs/scenarios/flight.yaml");
}

// The shipped flight scenario's off-nominal truth parameters, with `effects`.
inline Vehicle Truth(const Effects& effects) {
  Scenario s = ShippedFlightScenario();
  s.truth_effects = effects;
  return MakeTruthVehicle(Nominal().config, s);
}

inline ParameterOverride Value(double v) {
  ParameterOverride o;
  o.value = v;
  return o;
}

inline void ExpectWithinThreeStd(const DiscoveryResult& r, const Vehicle& truth,
                                 const std::string& name) {
  const ParameterSet& p = r.final.result.parameters;
  const IdentifiabilityReport& id = r.final.result.identifiability;
  for (size_t k = 0; k < id.names.size(); ++k) {
    if (id.names[k] != name) continue;
    ASSERT_TRUE(id.identifiable[k]) << name;
    // 3 std: a 0.3 % two-sided miss per parameter for a consistent estimator.
    EXPECT_NEAR(p.Value(name), truth.parameters.Value(name), 3 * id.std[k]) << name;
    return;
  }
  ADD_FAILURE() << name << " not estimated";
}

// The three gyro biases of a truth without the library's gyro_bias (the
// scenario's sensor model reads r `b_r` high) within 3 std of (0, 0, b_r).
inline void ExpectGyroBiasWithinThreeStd(const DiscoveryResult& r, const Vehicle& truth,
                                         double b_r) {
  std::map<std::string, ParameterOverride> biases;
  biases["b_r"] = Value(b_r);
  const Vehicle with_bias = WithEffect(truth, "gyro_bias", biases);
  for (const char* name : {"gyro_bias.b_p", "gyro_bias.b_q", "gyro_bias.b_r"}) {
    ExpectWithinThreeStd(r, with_bias, name);
  }
}

}  // namespace coaxid
