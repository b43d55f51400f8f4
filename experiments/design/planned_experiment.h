// A planned experiment simulated for its design: the logs it would give
// (flight and balance scenarios flown by the vehicle as the config knows it),
// the true states behind each flight row, the sensors' noise std from the
// scenarios, and each flight's envelope (how far it takes the vehicle).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "dynamics/vehicle.h"
#include "experiments/simulation/scenario.h"
#include "ident/estimation_log.h"
#include "ident/noise_weights.h"
#include "ident/output_error/output_error.h"

namespace coaxid {

// Peaks of a flight, relative to the hover trim: attitude (the larger of
// |phi| and |theta|), rotor-speed deviations, swashplate angles, as flown
// (controller plus excitation).
struct FlightEnvelope {
  double max_attitude_rad = 0;
  double max_rotor_speed_deviation_rad_s = 0;  // the larger of |omega_i - trim|
  double max_swashplate_rad = 0;               // the larger of |delta_cx|, |delta_cy|
  double max_height_deviation_m = 0;           // |height - the waypoint's height in force|
  // Mean squares about the trim of the same quantities (what the design's
  // local models take as linear in the components' powers): phi^2 + theta^2 pooled as one, omega deviations,
  // deltas, height off the waypoints.
  double ms_attitude = 0, ms_rotor_speed = 0, ms_swashplate = 0, ms_height = 0;
  nlohmann::json ToJson() const;
};

struct SimulatedExperiment {
  std::vector<EstimationLog> logs;                        // one per scenario, in order
  std::vector<std::vector<Eigen::VectorXd>> true_states;  // per log; empty for balance
  std::vector<Log> raw;                                   // the logs as simulated
  NoiseWeights noise;                                     // from the scenarios' sensors
  std::vector<FlightEnvelope> envelopes;                  // per log (zero for balance)
};

// Simulates every scenario with `vehicle` (the scenarios' truth sections are
// not used: a design is made for the vehicle as it is known). Throws
// InputError when a logged channel has no noise (its information would be
// infinite) or two scenarios give one channel different noise.
SimulatedExperiment SimulatePlannedExperiment(const Vehicle& vehicle,
                                              const std::vector<Scenario>& scenarios);

// The output-error precision of the planned experiment.
PredictedPrecision PredictPrecision(const Vehicle& vehicle, const SimulatedExperiment& experiment,
                                    const OutputErrorOptions& options);

// The flight's peaks from its true states and logged inputs.
FlightEnvelope EnvelopeOf(const Vehicle& vehicle, const FlightScenario& flight, const Log& log,
                          const std::vector<Eigen::VectorXd>& true_states);

}  // namespace coaxid
