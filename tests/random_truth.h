// A truth vehicle unlike the config, for tests that must not be tuned to
// one vehicle: every unknown base parameter of the config 10-30 % off, with
// random signs, drawn from `seed`.
#pragma once

#include <cstdint>
#include <random>
#include <string>

#include "dynamics/vehicle.h"

namespace coaxid {

inline Vehicle RandomTruth(const Vehicle& nominal, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> size(0.10, 0.30);
  std::bernoulli_distribution sign(0.5);
  Vehicle truth = nominal;
  for (const std::string& name : UnknownBaseParameterNames()) {
    const double factor = 1 + (sign(rng) ? 1 : -1) * size(rng);
    truth.parameters.SetValue(name, nominal.parameters.Value(name) * factor);
  }
  return truth;
}

}  // namespace coaxid
