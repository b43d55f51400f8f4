// An identification excitation designed for the parameters a user names
// (issue 16): a multisine shaped by frequency band, per input channel,
// flown in closed loop, within the limits a pilot or safety officer sets.
//
// How: the variables are the powers t_k of the components (input c, band
// b; t = 1 is the planned excitation's power spread flat over the bands).
// A design's shape is searched by local models: around the current design,
// one closed-loop flight per component with more power in it gives the
// information M and the flight's mean squares about trim as linear in t.
// The criterion (design_criterion.h) is convex in t, so a step is a small
// convex problem inside a trust region, solved by a log-barrier Newton
// method. Each step is flown; its size is then set by the tightest limit
// (peaks grow about as the square root of the power) and flown again,
// keeping the best flight within the limits. A design is judged by the
// precision predicted along its flown trajectory, never by a model of it.
// (A global model additive over components, from one probe flight each,
// was tried first and rejected: multiple-shooting information is not
// additive, docs/design.md.)
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "dynamics/vehicle.h"
#include "experiments/design/design_criterion.h"
#include "experiments/design/planned_experiment.h"
#include "experiments/simulation/scenario.h"

namespace coaxid {

// Peaks over the whole flight (waypoint transients included). NaN: the
// defaults, the planned flight's own attitude peak (the design flies no
// further), 20 % of the hover trim speed, 0.1 rad (half the model's
// swashplate range) and 0.5 m of height off the waypoints' (a lab's flight
// volume), or the planned flight's peaks where larger.
struct DesignLimits {
  double max_attitude_rad = std::numeric_limits<double>::quiet_NaN();
  double max_rotor_speed_deviation_rad_s = std::numeric_limits<double>::quiet_NaN();
  double max_swashplate_rad = std::numeric_limits<double>::quiet_NaN();
  double max_height_deviation_m = std::numeric_limits<double>::quiet_NaN();
  nlohmann::json ToJson() const;
};

struct FrequencyBand {
  double min_hz = 0, max_hz = 0;
};

struct ExcitationDesignOptions {
  // What is designed: a multisine shaped by frequency band (kMultisine), or
  // a 3211 pulse train (k3211): its unit pulse width, among pulse_widths_s,
  // and its pulse level per input.
  Excitation::Type excitation = Excitation::Type::kMultisine;
  std::vector<FrequencyBand> bands{{0.1, 0.5}, {0.5, 1.5}, {1.5, 4.0}};
  std::vector<double> pulse_widths_s{0.1, 0.15, 0.25, 0.4, 0.6, 1.0};
  DesignLimits limits;
  // The design aims at this share of each limit (the sensor noise
  // the controller feeds back moves the peaks from flight to flight).
  double margin = 0.9;
  // The excitation is off from 0.5 s before each waypoint change to this
  // long after it (0: always on): the controller's manoeuvre takes the
  // attitude near its peak there, and the room left to the limit is what
  // the excitation may use everywhere else.
  double quiet_after_waypoint_s = 3.0;
  int max_rounds = 8;  // local models made (each flies the design once per component)
  OutputErrorOptions output_error;
  std::function<void(const std::string&)> progress;
};

struct ExcitationDesign {
  int flight_index = 0;                 // the designed scenario among the planned ones
  Excitation::Type type = Excitation::Type::kMultisine;  // what was designed
  double pulse_s = 0;                   // 3211: the unit pulse width chosen
  std::vector<Scenario> reference, designed;
  SimulatedExperiment reference_run, designed_run;
  PredictedPrecision before, after;
  double criterion_before = 0, criterion_after = 0;
  DesignLimits limits;                  // as applied (NaN resolved)
  struct Component {
    std::string channel;
    FrequencyBand band;       // multisine
    double planned_rms = 0;   // multisine: the planned excitation's power in this band (t = 1)
    double designed_rms = 0;
    double planned_level = 0;   // 3211: pulse level (rad/s for rotor speeds, rad for angles)
    double designed_level = 0;
  };
  std::vector<Component> components;
  struct Round {
    double predicted_criterion = 0;  // by the local model (NaN: a start or resize flight)
    double flown_criterion = 0;      // along the flown design
    FlightEnvelope envelope;
    bool within_limits = false;
  };
  std::vector<Round> rounds;
  double seconds = 0;
};

// Designs the excitation of the first flight scenario of `scenarios`; the
// others (a balance campaign, further flights) are planned as they are and
// count in the joint precision. Throws InputError for a plan without a
// flight, a limit the unexcited flight already exceeds, or a named
// parameter the plan does not estimate; ComputationError when no flown
// design stays within the limits.
ExcitationDesign DesignExcitation(const Vehicle& vehicle, const std::vector<Scenario>& scenarios,
                                  const DesignCriterion& criterion,
                                  const ExcitationDesignOptions& options);

// The designed excitation's perturbation (omega1, omega2, delta_cx,
// delta_cy) at every row of the flight: what a flight computer adds to its
// controller's outputs.
Log ExcitationTimeSeries(const FlightScenario& flight);

}  // namespace coaxid
