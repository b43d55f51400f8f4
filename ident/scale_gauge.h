// The scale gauge of model.md decision 8, one notion for every estimator and
// the closing loop.
//
// Scaling d, gamma1, gamma2, Ixx, Iyy, Izz (and any moment-type effect
// parameter) by one common factor c leaves every flight output unchanged:
// the moments and the inertias scale together. Flight logs therefore fix
// only scale-free ratios (d beta / Ixx, gamma1 / Izz, Iyy / Ixx, J_r / Ixx,
// ...). A balance log (it measures the moments themselves), a prior on a
// member of the group, or a member the config holds fixes the scale. When
// none does, the estimators hold d at its config value (or the prior's) and
// report the ratios with their std.
//
// FindScaleDirection checks the invariance on the model itself rather than
// trusting a list: with v_i = d theta_i / d log c, it means
//     sum_i v_i d[f; y]/d theta_i = 0
// at every state and input (f the state derivative, y the flight outputs).
// v_i = theta_i on the six base parameters; the enabled effects' share is
// solved by least squares over sample points (a moment-type effect parameter
// gets v_e = theta_e, any other 0), and the residual says whether the
// invariance holds.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "core/input_hold.h"
#include "core/parameters.h"
#include "dynamics/state.h"
#include "dynamics/vehicle_model.h"
#include "ident/estimation_log.h"

namespace coaxid {

struct ModelSample {
  Eigen::VectorXd x;  // the model's states (effect states after the 12)
  HeldInput u;
};

// Operating points for the invariance check: up to 20 rows spread over the
// flight logs, states as measured (0 where absent), the rows' inputs (as
// logged: a lag's history does not enter a scale). An effect's own states
// (never logged) are set to 0.01, so that the parameters acting through
// them show in the check.
std::vector<ModelSample> SamplePoints(const std::vector<EstimationLog>& logs,
                                      const VehicleModel& model);

struct ScaleDirection {
  bool exists = false;
  // Full theta size: v_i = d theta_i / d log c (0 outside the group).
  Eigen::VectorXd direction;
  std::vector<int> group;  // indices with v_i != 0, base parameters first
  // |sum_i v_i d[f; y]/d theta_i| relative to the size of its terms.
  double residual = 0;
};

// Candidates: every unknown base parameter and effect parameter (known
// constants are never part of it). samples: operating points (at least one).
ScaleDirection FindScaleDirection(const VehicleModel& model, const ParameterSet& parameters,
                                  const std::vector<ModelSample>& samples);

// What an estimator does about the scale.
enum class ScaleAnchor {
  kHubDistance,  // hold d when nothing else fixes the scale (model.md decision 8)
  kNone,         // estimate every member; the undetermined direction is reported
};

struct ScaleGauge {
  ScaleDirection direction;  // exists only when flight logs are fitted
  std::vector<std::string> group;  // names of the group's members
  // What fixes the scale: "balance log", "prior on NAME", "config: NAME held",
  // "held: d" (this gauge held it), or "nothing" (kNone, flight logs alone).
  std::string fixed_by;
  std::string held;  // the parameter this gauge held for the scale ("d"), or empty
  // The one held member whose value alone sets the scale (`held`, or the
  // config's only held member), or empty. An estimator may solve with it
  // free and then move the solution along the scale back to its value.
  std::string held_member;
  std::string note;  // for people
  nlohmann::json ToJson() const;
};

// Decides the gauge for fitting `logs` and applies it to *parameters: with
// flight logs, no balance log measuring a moment, no member of the group
// held by the config and none named in `prior_names`, and anchor
// kHubDistance, d is marked not estimated (at its current value: the
// config's, or the prior's if the caller set it).
ScaleGauge FixScaleGauge(const VehicleModel& model, const std::vector<EstimationLog>& logs,
                         const std::vector<std::string>& prior_names, ScaleAnchor anchor,
                         ParameterSet* parameters);

// A scale-free product of parameters, prod theta_i^power_i, with its std by
// the delta method.
struct ScaleFreeRatio {
  std::string name;                         // "d*beta/Ixx"
  std::vector<std::pair<int, int>> powers;  // (theta index, exponent)
  double value = 0, std = 0;
  double Evaluate(const ParameterSet& parameters) const;
};

// The ratios flight logs determine: d*beta/Ixx, d*beta/Iyy, gamma1/Izz,
// gamma2/Izz, Iyy/Ixx, Izz/Ixx and every moment-type effect parameter over
// Ixx, at `parameters`. covariance: of the free parameters (free_indices),
// unscaled; a parameter not free contributes no variance. A ratio that moves
// along a direction the covariance leaves out (zero variance: undetermined
// by the logs) gets std NaN: not determined. Empty when the gauge has no
// direction (no flight log, or the invariance does not hold).
std::vector<ScaleFreeRatio> ScaleFreeRatios(const ScaleGauge& gauge,
                                            const ParameterSet& parameters,
                                            const std::vector<int>& free_indices,
                                            const Eigen::MatrixXd& covariance);

// Marks the parameter the gauge held in a report's "parameters" object:
// "estimated": false, "std": null, "held_for_the_scale": true and a "source"
// that says so (never "estimated").
void MarkHeldForTheScale(const ScaleGauge& gauge, nlohmann::json* parameters);

// report.json "ratios": {"d*beta/Ixx": {"value": ..., "std": ...}, ...}.
nlohmann::json RatiosJson(const std::vector<ScaleFreeRatio>& ratios);

// The printed table's lines for the scale: the held parameter
// ("  d   1.0e-01   held for the scale ...") and each ratio with its std.
std::string ScaleTableText(const ScaleGauge& gauge, const ParameterSet& parameters,
                           const std::vector<ScaleFreeRatio>& ratios);

}  // namespace coaxid
