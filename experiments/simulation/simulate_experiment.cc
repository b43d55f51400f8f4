#include "experiments/simulation/simulate_experiment.h"

#include <cmath>
#include <cstdio>
#include <random>

#include "core/errors.h"
#include "dynamics/outputs.h"
#include "dynamics/trim.h"
#include "dynamics/vehicle_ode.h"
#include "experiments/simulation/excitation.h"
#include "experiments/simulation/hover_controller.h"
#include "experiments/simulation/outside_library_loads.h"

namespace coaxid {

Vehicle MakeTruthVehicle(const VehicleConfig& config, const Scenario& scenario) {
  VehicleConfig truth_config = config;
  for (const auto& effect : scenario.truth_effects) {
    bool present = false;
    for (auto& [name, overrides] : truth_config.effects) {
      if (name == effect.first) {
        present = true;
        for (const auto& kv : effect.second) overrides[kv.first] = kv.second;
      }
    }
    if (!present) truth_config.effects.push_back(effect);
  }
  Vehicle truth = MakeVehicle(truth_config);
  for (const auto& [name, value] : scenario.truth_parameters) {
    if (!truth.parameters.Has(name)) {
      throw InputError(scenario.name + ": truth.parameters: unknown parameter '" + name + "'");
    }
    truth.parameters.SetValue(name, value);
  }
  const OutsideLibraryStrengths outside =
      ParseOutsideLibrary(scenario.truth_outside_library, scenario.name + ": truth.outside_library");
  if (outside.Any()) truth.model.SetTruthOnlyLoads(std::make_shared<OutsideLibraryLoads>(outside));
  return truth;
}

nlohmann::json TruthJson(const Vehicle& truth) {
  nlohmann::json parameters = nlohmann::json::object();
  for (int i = 0; i < kNumBaseParameters; ++i) parameters[truth.parameters[i].name] = truth.parameters[i].value;
  nlohmann::json effects = nlohmann::json::object();
  for (const std::string& name : truth.EffectNames()) {
    nlohmann::json p = nlohmann::json::object();
    for (const auto& spec : EffectLibrary()[EffectIndex(name)].parameters) {
      p[spec.name] = truth.parameters.Value(name + "." + spec.name);
    }
    effects[name] = p;
  }
  return {{"parameters", parameters}, {"effects", effects}};
}

namespace {

std::string FormatRate(double hz) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", hz);
  return text;
}

double NoiseStd(const std::map<std::string, double>& table, const std::string& column) {
  auto it = table.find(column);
  return it == table.end() ? 0.0 : it->second;
}

}  // namespace

std::vector<InputVector> BalanceHolds(const BalanceScenario& s) {
  // The staircase: every (omega1, omega2) pair; swashplate sweeps only where
  // the lower rotor turns (the swashplate tilts the lower rotor, eq. 7).
  std::vector<InputVector> holds;
  for (double w1 : s.omega1) {
    for (double w2 : s.omega2) {
      if (w2 == 0) {
        holds.push_back({w1, w2, 0, 0});
        continue;
      }
      for (double dx : s.delta_cx) {
        for (double dy : s.delta_cy) holds.push_back({w1, w2, dx, dy});
      }
    }
  }
  for (const auto& h : s.holds) holds.push_back({h[0], h[1], h[2], h[3]});
  return holds;
}

Log SimulateBalance(const Vehicle& truth, const BalanceScenario& s, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const Eigen::VectorXd theta = truth.parameters.Values();
  const std::vector<InputVector> holds = BalanceHolds(s);
  std::vector<std::string> loads = {"X", "Y", "Z", "L", "M", "N"};
  if (s.per_rotor) loads.insert(loads.end(), {"Z1", "Z2", "N1", "N2"});

  const int per_hold = std::max(1, static_cast<int>(std::lround(s.hold_s * s.rate_hz)));
  Log log;
  log.kind = LogKind::kBalance;
  std::vector<std::vector<double>> cols(1 + 4 + loads.size());
  double t = 0;
  for (const InputVector& u : holds) {
    const AeroLoads<double> a = truth.model.Loads(theta.data(), u.data(), Setting::kBalance,
                                                  static_cast<const double*>(nullptr));
    const double exact[10] = {a.force_B[0], a.force_B[1], a.force_B[2], a.moment_B[0],
                              a.moment_B[1], a.moment_B[2], a.Z1, a.Z2, a.N1, a.N2};
    // A steady point is the mean of the hold's samples: its noise shrinks by sqrt(n).
    const int rows = s.steady_points ? 1 : per_hold;
    const double shrink = s.steady_points ? 1.0 / std::sqrt(static_cast<double>(per_hold)) : 1.0;
    for (int k = 0; k < rows; ++k) {
      cols[0].push_back(t);
      for (int i = 0; i < 4; ++i) cols[1 + i].push_back(u[i]);
      for (size_t j = 0; j < loads.size(); ++j) {
        cols[5 + j].push_back(exact[j] + shrink * NoiseStd(s.noise_std, loads[j]) * normal(rng));
      }
      t += s.steady_points ? s.hold_s : 1.0 / s.rate_hz;
    }
  }
  log.columns = {"t", "omega1", "omega2", "delta_cx", "delta_cy"};
  log.columns.insert(log.columns.end(), loads.begin(), loads.end());
  log.values = std::move(cols);
  if (!s.steady_points) log.metadata["rate_hz"] = FormatRate(s.rate_hz);
  log.metadata["layout"] = s.steady_points ? "steady_points" : "time_series";
  return log;
}

namespace {

Waypoint TargetAt(const std::vector<Waypoint>& waypoints, double t) {
  Waypoint target = waypoints.front();
  for (const Waypoint& w : waypoints) {
    if (w.t_s <= t) target = w;
  }
  return target;
}

}  // namespace

IntegratorOptions FlightSimulationIntegrator() {
  IntegratorOptions options;
  options.method = IntegratorOptions::Method::kExplicitRungeKutta;
  options.relative_tolerance = 1e-7;
  options.absolute_tolerance = 1e-9;
  return options;
}

Log SimulateFlight(const Vehicle& truth, const FlightScenario& s, uint64_t seed,
                   const IntegratorOptions& integrator_options,
                   std::vector<Eigen::VectorXd>* true_states) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const Eigen::VectorXd theta = truth.parameters.Values();
  const Waypoint start = s.waypoints.front();
  const HoverTrim trim = TrimHover(truth.model, theta, start.height, start.heading);

  const double dt = 1.0 / s.rate_hz;
  const int steps = static_cast<int>(std::floor(s.duration_s * s.rate_hz + 1e-9)) + 1;
  HoverController controller(s.gains, trim.input, dt);
  const ExcitationSignal excitation(s.excitation);
  VehicleOde ode(truth.model, theta);
  Integrator integrator(ode, integrator_options);

  // Sensor model: truth + bias + white noise, per column.
  auto sensed = [&](const std::string& column, double truth_value) {
    return truth_value + NoiseStd(s.bias, column) + NoiseStd(s.noise_std, column) * normal(rng);
  };
  static const char* kInputNames[4] = {"omega1", "omega2", "delta_cx", "delta_cy"};
  std::vector<std::string> columns = {"t", "omega1", "omega2", "delta_cx", "delta_cy"};
  columns.insert(columns.end(), s.columns.begin(), s.columns.end());
  std::vector<std::vector<double>> values(columns.size());
  for (auto& v : values) v.reserve(steps);

  std::vector<int> column_channel;  // the output channel of each logged column
  for (const std::string& name : s.columns) column_channel.push_back(FlightChannelIndex(name));

  Eigen::VectorXd x = trim.state;
  // The commanded inputs as the truth's actuators apply them (servo, motor lags).
  const InputVector lag = truth.model.InputLags(theta.data());
  HeldInput held;
  if (true_states) {
    true_states->clear();
    true_states->reserve(steps);
  }
  for (int k = 0; k < steps; ++k) {
    const double t = k * dt;
    if (true_states) true_states->push_back(x);
    // Noisy measurement of the state at t_k; the controller acts on it. The
    // truth's measurement effects (a gyro bias) come first: they do not
    // depend on the inputs.
    double read[kNumFlightChannels] = {};
    for (int i = 0; i < kNumStates; ++i) read[i] = x[i];
    truth.model.AddToFlightMeasurements(theta.data(), read);
    double measured[kNumStates];
    for (int i = 0; i < kNumStates; ++i) measured[i] = sensed(StateName(i), read[i]);
    const Measurement y{measured[kX],   measured[kY],     measured[kZ],   measured[kU],
                        measured[kV],   measured[kW],     measured[kPhi], measured[kTheta],
                        measured[kPsi], measured[kP],     measured[kQ],   measured[kR]};
    InputVector u = controller.Update(y, TargetAt(s.waypoints, t));
    const InputVector e = excitation.At(t);
    for (int i = 0; i < 4; ++i) u[i] += e[i];
    // Actuator limits: rotor speeds in [0, 400] rad/s, swashplate within +-0.2 rad (model.md).
    u[0] = std::clamp(u[0], 0.0, 400.0);
    u[1] = std::clamp(u[1], 0.0, 400.0);
    u[2] = std::clamp(u[2], -0.2, 0.2);
    u[3] = std::clamp(u[3], -0.2, 0.2);

    // Log row k: inputs held on [t_k, t_{k+1}), outputs at t_k (accelerometer
    // with row k's inputs, model.md decision 7).
    values[0].push_back(t);
    for (int i = 0; i < 4; ++i) values[1 + i].push_back(sensed(kInputNames[i], u[i]));
    // The states are logged as the controller measured them; the
    // accelerometer is measured here, with row k's inputs (decision 7).
    held = k == 0 ? HeldInput::Steady(u, t) : NextHeldInput(held, lag, u, t);
    double outputs[kNumFlightChannels];
    FlightOutputsAt(truth.model, theta.data(), x.data(), held, outputs);
    for (size_t c = 0; c < s.columns.size(); ++c) {
      const int channel = column_channel[c];
      values[5 + c].push_back(channel < kNumStates ? measured[channel]
                                                   : sensed(s.columns[c], outputs[channel]));
    }
    if (k + 1 == steps) break;

    ode.SetInput(held);
    Eigen::VectorXd next;
    if (!integrator.Reset(t, x) || !integrator.AdvanceTo(t + dt, &next)) {
      throw ComputationError("flight simulation: integrator failed at t = " + std::to_string(t) +
                             " s: " + integrator.last_error());
    }
    x = next;
    if (std::fabs(x[kPhi]) > 1.0 || std::fabs(x[kTheta]) > 1.0 || !x.allFinite()) {
      throw ComputationError("flight simulation left the near-hover envelope at t = " +
                             std::to_string(t + dt) +
                             " s (attitude beyond 1 rad): the controller cannot hold this "
                             "vehicle; lower the excitation or retune the gains");
    }
  }
  Log log;
  log.kind = LogKind::kFlight;
  log.columns = columns;
  log.values = std::move(values);
  log.metadata["rate_hz"] = FormatRate(s.rate_hz);
  return log;
}

Log SimulateScenario(const Vehicle& truth, const Scenario& scenario,
                     const IntegratorOptions& integrator) {
  Log log = scenario.kind == Scenario::Kind::kBalance
                ? SimulateBalance(truth, scenario.balance, scenario.seed)
                : SimulateFlight(truth, scenario.flight, scenario.seed, integrator);
  log.metadata["vehicle"] = truth.config.vehicle;
  log.metadata["source"] = "coaxid simulate, scenario " + scenario.name + ", seed " +
                           std::to_string(scenario.seed);
  return log;
}

}  // namespace coaxid
