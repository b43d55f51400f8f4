// Simulated experiments: a truth vehicle (the config's vehicle with the
// scenario's parameter overrides and effects) run through a scenario, giving a
// log in the log format. Reproducible from the seed.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include <nlohmann/json.hpp>

#include "core/log.h"
#include "dynamics/integrator.h"
#include "dynamics/vehicle.h"
#include "experiments/simulation/scenario.h"

namespace coaxid {

// The config's vehicle with the scenario's truth overrides and effects.
// Throws InputError on an unknown parameter or effect.
Vehicle MakeTruthVehicle(const VehicleConfig& config, const Scenario& scenario);

// truth.json of cli-and-reports.md: every parameter (known and unknown) and
// the effects present with their parameters.
nlohmann::json TruthJson(const Vehicle& truth);

// The holds of a balance campaign, in the order it flies them: the grid's
// (omega1 x omega2, swashplate sweeps where the lower rotor turns), then
// those listed one by one.
std::vector<InputVector> BalanceHolds(const BalanceScenario& scenario);

// The paper's static experiment (sect. 3): staircase holds, balance loads of
// eqs. 57-63 (plus effects) with additive Gaussian noise.
Log SimulateBalance(const Vehicle& truth, const BalanceScenario& scenario, uint64_t seed);

// Closed-loop flight from hover trim at the first waypoint, the controller
// fed by noisy sensors, excitation added to its outputs. Throws
// ComputationError if the integrator fails or the flight leaves the
// near-hover envelope (attitude beyond 1 rad). true_states (optional): the
// true state at every row (what the sensors measured before their noise).
// The integrator the flight simulations use unless told otherwise: the explicit Runge-Kutta
// method at rtol 1e-7, atol 1e-9. The controller's zero-order hold restarts the integration
// every sample; a one-step method loses nothing there, and a 60 s flight at 200 Hz takes about
// half the time it takes with Adams at the same tolerances
// (bench/experiments/simulation/flight_bench.cc).
IntegratorOptions FlightSimulationIntegrator();

Log SimulateFlight(const Vehicle& truth, const FlightScenario& scenario, uint64_t seed,
                   const IntegratorOptions& integrator = FlightSimulationIntegrator(),
                   std::vector<Eigen::VectorXd>* true_states = nullptr);

// Dispatches on the scenario kind; adds metadata (vehicle, rate_hz, source).
Log SimulateScenario(const Vehicle& truth, const Scenario& scenario,
                     const IntegratorOptions& integrator = FlightSimulationIntegrator());

}  // namespace coaxid
