// One run of a randomised study (spec key `randomise`, docs/study.md): the
// truth vehicle, truth effects and flights drawn from the run's seed. A pure
// function of (spec, seed), like every run.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "experiments/simulation/scenario.h"
#include "experiments/studies/spec.h"

namespace coaxid {

struct RandomDraw {
  // "none", the sorted library effects joined by '+' ("gyroscopic+wind"), or
  // "outside:NAME" for a load outside the library.
  std::string truth_label;
  std::vector<std::string> effects;  // library effects in the truth
  std::string outside;               // the outside-library load, or empty
  std::vector<Scenario> scenarios;   // estimation: the flight, then the balance if drawn
  bool has_held_out = false;
  Scenario held_out;                 // a 3211 flight of the same truth
  nlohmann::json description;        // what was drawn, for the run's record
};

// Truth: each free parameter of the config at value x (1 + s u), u uniform in
// truth_offset, s a random sign; gamma2 then set so the hover trim at the
// first waypoint has the drawn |omega1 - omega2| (random sign). Effects: the
// class by its weight, effects uniformly from `effects`, each parameter at its
// typical strength times a factor in effect_strength (random sign where the
// bounds allow both). Flight: the spec's flight scenario as template (rate,
// sensors, noise, controller) with a drawn duration, excitation, swashplate
// amplitude and four waypoints in the hover or low band (always low with
// ground_effect). An outside-library load takes a strength from its range,
// yaw_from_swashplate with a random sign, thrust_from_climb_rate positive
// (thrust falling with the climb rate). With controller_gain_factor or
// sensor_noise_factor other than [1, 1], each controller gain and each logged
// channel's noise std of the flight and the held-out flight takes its own
// log-uniform factor. Streams: flight MixSeed(seed, 0), balance 1, held out
// 2, the draw itself 2000, controller and sensors 2001. Throws
// ComputationError if no trim exists.
RandomDraw DrawRun(const StudySpec& spec, uint64_t seed);

}  // namespace coaxid
