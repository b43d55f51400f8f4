// Scenario files (configs/scenarios/*.yaml): what experiment to simulate and
// how. Two kinds, as in log-format.md:
//  - balance: the paper's static experiment (sect. 3): staircase holds over a
//    grid of omega1 x omega2 (single-rotor runs included) and swashplate
//    angles, loads measured by a strain-gauge balance with noise;
//  - flight: closed-loop hover and near-hover flight with identification
//    excitation added to the controller's outputs, noisy sensors.
// Either may switch effects on in the truth model and override the truth's
// parameters (a real vehicle differs from its nominal config).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/vehicle_config.h"

namespace coaxid {

struct BalanceScenario {
  double rate_hz = 100;       // balance sampling rate
  double hold_s = 2.0;        // duration of each constant-input hold
  std::vector<double> omega1{0, 110, 135, 160};   // rad/s
  std::vector<double> omega2{0, 110, 135, 160};   // rad/s
  std::vector<double> delta_cx{-0.15, 0, 0.15};   // rad
  std::vector<double> delta_cy{-0.15, 0, 0.15};   // rad
  // Holds listed one by one, (omega1, omega2, delta_cx, delta_cy), after
  // the grid's (a campaign planned hold by hold; empty speed lists: no grid).
  std::vector<std::array<double, 4>> holds;
  bool steady_points = false;  // one averaged row per hold instead of a time series
  bool per_rotor = true;       // also log Z1, Z2, N1, N2
  // Noise standard deviation per load column [N, N m].
  std::map<std::string, double> noise_std{{"X", 0.01},  {"Y", 0.01},   {"Z", 0.02},
                                          {"L", 5e-4},  {"M", 5e-4},   {"N", 2e-4},
                                          {"Z1", 0.01}, {"Z2", 0.01},  {"N1", 1e-4},
                                          {"N2", 1e-4}};
};

struct Excitation {
  enum class Type { kNone, kMultisine, k3211, kDoublet };
  Type type = Type::kMultisine;
  double start_s = 2.0;  // excitation starts after the vehicle settles
  // Amplitude per input channel (peak), rad/s for rotor speeds, rad for angles.
  std::map<std::string, double> amplitude{
      {"omega1", 4.0}, {"omega2", 4.0}, {"delta_cx", 0.02}, {"delta_cy", 0.02}};
  double min_hz = 0.2, max_hz = 4.0;  // multisine band
  double period_s = 20.0;             // multisine period (frequency resolution 1/period)
  double pulse_s = 0.25;              // 3211 and doublet: unit pulse width
  // Multisine shaped by frequency band (what `coaxid design` writes): when
  // non-empty it replaces amplitude, min_hz and max_hz. Each band's
  // harmonics of 1/period are dealt round-robin to the four channels; a
  // channel's sines in a band share its rms there (rms over a period of that
  // band's part of the signal: rad/s for rotor speeds, rad for angles), and
  // its phases follow Schroeder's rule for its whole amplitude spectrum (a
  // low crest factor).
  struct Band {
    double min_hz = 0, max_hz = 0;
    std::map<std::string, double> rms;  // by input channel; a missing channel is 0
  };
  std::vector<Band> bands;
  // Windows [from_s, to_s] in which the excitation is off (planned
  // manoeuvres flown without it), faded out and in over quiet_ramp_s.
  std::vector<std::array<double, 2>> quiet;
  static constexpr double quiet_ramp_s = 0.5;
};

struct ControllerGains {
  double att_kp = 1.0, att_kd = 0.17;        // swashplate rad per rad, per rad/s
  double alt_kp = 30.0, alt_kd = 20.0, alt_ki = 5.0;  // rotor rad/s per m, per m/s, per m s
  double yaw_kp = 1.7, yaw_kd = 1.2;         // differential rad/s per rad, per rad/s
  double pos_kp = 0.6, pos_kd = 1.0;         // desired acceleration m/s^2 per m, per m/s
  double max_tilt = 0.15;                    // rad, position loop command limit

  // Every field by its scenario key (controller.*), max_tilt last.
  std::vector<std::pair<std::string, double*>> Fields() {
    return {{"att_kp", &att_kp}, {"att_kd", &att_kd}, {"alt_kp", &alt_kp},
            {"alt_kd", &alt_kd}, {"alt_ki", &alt_ki}, {"yaw_kp", &yaw_kp},
            {"yaw_kd", &yaw_kd}, {"pos_kp", &pos_kp}, {"pos_kd", &pos_kd},
            {"max_tilt", &max_tilt}};
  }
};

struct Waypoint {
  double t_s = 0;          // from this time on
  double north = 0, east = 0, height = 1.5, heading = 0;  // m, m, m, rad
};

struct FlightScenario {
  double duration_s = 60;
  double rate_hz = 200;  // controller and log rate (inputs are zero-order hold at this rate)
  std::vector<Waypoint> waypoints{Waypoint{}};
  ControllerGains gains;
  Excitation excitation;
  // Sensor model: noise standard deviation and constant bias per logged
  // column; columns logged (t and inputs always are).
  std::vector<std::string> columns{"x", "y", "z", "u", "v", "w", "phi", "theta", "psi",
                                   "p", "q", "r", "ax", "ay", "az"};
  std::map<std::string, double> noise_std{
      {"x", 0.005},  {"y", 0.005},    {"z", 0.005},   {"u", 0.02},  {"v", 0.02},
      {"w", 0.02},   {"phi", 0.003},  {"theta", 0.003}, {"psi", 0.003}, {"p", 0.01},
      {"q", 0.01},   {"r", 0.01},     {"ax", 0.1},    {"ay", 0.1},  {"az", 0.1},
      {"omega1", 0.0}, {"omega2", 0.0}, {"delta_cx", 0.0}, {"delta_cy", 0.0}};
  std::map<std::string, double> bias;
};

struct Scenario {
  enum class Kind { kBalance, kFlight };
  Kind kind = Kind::kFlight;
  std::string name;                 // file stem or built-in name
  uint64_t seed = 1;
  BalanceScenario balance;
  FlightScenario flight;
  // Truth model: parameter overrides (by canonical name, effect parameters as
  // "effect.param") and effects switched on (name -> parameter overrides).
  std::map<std::string, double> truth_parameters;
  std::vector<std::pair<std::string, std::map<std::string, ParameterOverride>>> truth_effects;
  // Loads outside the effect library (experiments/simulation/outside_library_loads.h).
  std::map<std::string, double> truth_outside_library;
};

// A scenario file, or one of the built-in names "balance" and "flight".
// Throws InputError naming the file and entry on anything unknown or invalid.
Scenario LoadScenario(const std::string& path_or_name);
Scenario ParseScenario(const std::string& yaml_text, const std::string& source);

}  // namespace coaxid
