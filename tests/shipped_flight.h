// The shipped vehicle and flight scenario for tests that fit random truths:
// configs/glmav.yaml, and configs/scenarios/flight.yaml (a closed-loop
// flight with multisine excitation on all four inputs) cut to `seconds` and
// excited from its start.
#pragma once

#include <string>

#include "experiments/simulation/simulate_experiment.h"

namespace coaxid {

inline Vehicle ShippedVehicle() {
  return LoadVehicle(std::string(COAXID_SOURCE_DIR) + "/configs/glmav.yaml");
}

inline FlightScenario ExcitedShippedFlight(double seconds) {
  FlightScenario flight =
      LoadScenario(std::string(COAXID_SOURCE_DIR) + "/configs/scenarios/flight.yaml").flight;
  flight.duration_s = seconds;
  flight.excitation.start_s = 0;
  return flight;
}

}  // namespace coaxid
