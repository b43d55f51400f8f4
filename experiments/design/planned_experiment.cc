#include "experiments/design/planned_experiment.h"

#include <algorithm>
#include <cmath>

#include "core/errors.h"
#include "dynamics/state.h"
#include "dynamics/trim.h"
#include "experiments/simulation/simulate_experiment.h"

namespace coaxid {

nlohmann::json FlightEnvelope::ToJson() const {
  return {{"max_attitude_rad", max_attitude_rad},
          {"max_rotor_speed_deviation_rad_s", max_rotor_speed_deviation_rad_s},
          {"max_swashplate_rad", max_swashplate_rad},
          {"max_height_deviation_m", max_height_deviation_m},
          {"rms_attitude_rad", std::sqrt(ms_attitude)},
          {"rms_rotor_speed_deviation_rad_s", std::sqrt(ms_rotor_speed)},
          {"rms_swashplate_rad", std::sqrt(ms_swashplate)},
          {"rms_height_deviation_m", std::sqrt(ms_height)}};
}

FlightEnvelope EnvelopeOf(const Vehicle& vehicle, const FlightScenario& flight, const Log& log,
                          const std::vector<Eigen::VectorXd>& true_states) {
  const Waypoint& start = flight.waypoints.front();
  const HoverTrim trim = TrimHover(vehicle.model, vehicle.parameters.Values(), start.height,
                                   start.heading);
  const std::vector<double>& w1 = log.Column("omega1");
  const std::vector<double>& w2 = log.Column("omega2");
  const std::vector<double>& dx = log.Column("delta_cx");
  const std::vector<double>& dy = log.Column("delta_cy");
  const std::vector<double>& t = log.Column("t");
  FlightEnvelope e;
  const int n = log.NumRows();
  for (int k = 0; k < n; ++k) {
    const Eigen::VectorXd& x = true_states[k];
    e.max_attitude_rad = std::max({e.max_attitude_rad, std::fabs(x[kPhi]), std::fabs(x[kTheta])});
    const double d1 = w1[k] - trim.input[0], d2 = w2[k] - trim.input[1];
    e.max_rotor_speed_deviation_rad_s =
        std::max({e.max_rotor_speed_deviation_rad_s, std::fabs(d1), std::fabs(d2)});
    e.max_swashplate_rad = std::max({e.max_swashplate_rad, std::fabs(dx[k]), std::fabs(dy[k])});
    double target_height = flight.waypoints.front().height;
    for (const Waypoint& w : flight.waypoints) {
      if (w.t_s <= t[k]) target_height = w.height;
    }
    const double dh = -x[kZ] - target_height;
    e.max_height_deviation_m = std::max(e.max_height_deviation_m, std::fabs(dh));
    e.ms_height += dh * dh / n;
    e.ms_attitude += (x[kPhi] * x[kPhi] + x[kTheta] * x[kTheta]) / (2.0 * n);
    e.ms_rotor_speed += (d1 * d1 + d2 * d2) / (2.0 * n);
    e.ms_swashplate += (dx[k] * dx[k] + dy[k] * dy[k]) / (2.0 * n);
  }
  return e;
}

namespace {

// Adds the scenario's noise std of each channel the log holds.
void AddNoise(const Scenario& scenario, const EstimationLog& log, NoiseWeights* noise) {
  const std::map<std::string, double>& table = scenario.kind == Scenario::Kind::kFlight
                                                   ? scenario.flight.noise_std
                                                   : scenario.balance.noise_std;
  for (const std::string& channel : log.channel_names) {
    auto it = table.find(channel);
    double std = it == table.end() ? 0.0 : it->second;
    // A steady point is the mean of a hold: its noise shrinks by sqrt(rows).
    if (scenario.kind == Scenario::Kind::kBalance && scenario.balance.steady_points) {
      const double rows = std::max(1.0, std::round(scenario.balance.hold_s *
                                                   scenario.balance.rate_hz));
      std /= std::sqrt(rows);
    }
    if (!(std > 0)) {
      throw InputError(scenario.name + ": channel '" + channel +
                       "' is logged without noise (noise_std 0): a design needs every logged "
                       "channel's noise std");
    }
    auto [at, inserted] = noise->std.emplace(channel, std);
    if (!inserted && std::fabs(at->second / std - 1) > 1e-12) {
      throw InputError(scenario.name + ": channel '" + channel +
                       "' has a noise std other than another planned log's; plan one noise per "
                       "channel");
    }
  }
}

}  // namespace

SimulatedExperiment SimulatePlannedExperiment(const Vehicle& vehicle,
                                              const std::vector<Scenario>& scenarios) {
  if (scenarios.empty()) throw InputError("a design needs at least one scenario");
  SimulatedExperiment out;
  for (const Scenario& scenario : scenarios) {
    std::vector<Eigen::VectorXd> states;
    Log log;
    if (scenario.kind == Scenario::Kind::kFlight) {
      log = SimulateFlight(vehicle, scenario.flight, scenario.seed, FlightSimulationIntegrator(),
                          &states);
    } else {
      log = SimulateBalance(vehicle, scenario.balance, scenario.seed);
    }
    log.source = scenario.name;
    EstimationLog estimation = MakeEstimationLog(log);
    estimation.source = estimation.name = scenario.name;
    AddNoise(scenario, estimation, &out.noise);
    out.envelopes.push_back(scenario.kind == Scenario::Kind::kFlight
                                ? EnvelopeOf(vehicle, scenario.flight, log, states)
                                : FlightEnvelope{});
    out.logs.push_back(std::move(estimation));
    out.true_states.push_back(std::move(states));
    out.raw.push_back(std::move(log));
  }
  return out;
}

PredictedPrecision PredictPrecision(const Vehicle& vehicle, const SimulatedExperiment& experiment,
                                    const OutputErrorOptions& options) {
  return PredictOutputErrorPrecision(vehicle, experiment.logs, experiment.true_states,
                                     experiment.noise, options);
}

}  // namespace coaxid
