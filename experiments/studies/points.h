// What one run of a study simulates and where its estimators start: the
// spec's scenarios with the sweep point applied and the run's seeds, and the
// config's vehicle with the spec's free parameters (and, for an
// initial_error sweep, start values perturbed per seed).
#pragma once

#include <cstdint>
#include <vector>

#include "dynamics/vehicle.h"
#include "experiments/simulation/scenario.h"
#include "experiments/studies/spec.h"

namespace coaxid {

// A well-mixed 64-bit value of (seed, stream) (SplitMix64 finaliser): one
// independent random stream per scenario and purpose of a run.
uint64_t MixSeed(uint64_t seed, uint64_t stream);

// The spec's scenarios at a sweep point, scenario i seeded with
// MixSeed(seed, i). noise_scale scales every noise std; excitation_scale the
// flight excitation amplitudes and the balance swashplate grid;
// excitation_type and log_length_s the flight excitation and duration;
// sample_rate_hz every scenario's rate; effect_strength sets the truth
// effect's parameter (adding the effect where absent, removing it at 0).
// A randomised study's scenarios are DrawRun(spec, seed).scenarios.
std::vector<Scenario> PointScenarios(const StudySpec& spec, int point, uint64_t seed);

// The estimators' start: the config's vehicle, only the spec's `estimate`
// parameters free (all the config's free ones without it). With an
// initial_error sweep, each free parameter starts at its config value times
// (1 + e u), u uniform in [-1, 1] from the seed, clamped to its bounds.
Vehicle StartVehicle(const StudySpec& spec, int point, uint64_t seed);

}  // namespace coaxid
