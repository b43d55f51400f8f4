// Plausibility verdicts (issue 17): does a fitted model describe the
// vehicle? A fit can converge and still be meaningless: on a vehicle whose
// physics the model lacks (a stabilizer bar), the estimator drives d to its
// bound and the inertias far above anything the vehicle's mass and size
// allow, so that the swashplate does nothing, and predicts p and q no better
// than their mean. Every report (identify, discover, compare, demo) carries
// the verdict and says it on stdout.
//
// What is judged, for the estimated parameters only (known constants are the
// user's measurements):
//   - at or beyond a bound of the config: the data pushed the parameter to
//     its limit (methods without bounds, linear_kf and ekf, may pass it);
//   - outside a physical range derived from the config:
//       inertias: no rigid body of mass m inside a sphere of radius r about G
//       has a moment of inertia above m r^2, with r = sqrt(R^2 + (l/2)^2)
//       (rotor disc radius R, body length l, G mid-body); principal moments
//       obey the triangle inequality (Ixx + Iyy >= Izz and its turns);
//       d: the lower hub lies inside that sphere (0 < d <= r);
//       Cx, Cy, Cz: bluff-body drag coefficients on the paper's reference
//       areas lie in [0.05, 3] (a flat plate broadside is 2);
//       sigma0: a coaxial rotor's interference loss at equal speeds in
//       [0, 0.4] (measured lower-rotor losses are 10-25 %);
//       gamma1 / alpha, gamma2 / beta: a rotor's torque-to-thrust ratio is
//       (C_Q / C_T) R, with C_Q / C_T in [0.02, 0.5] for rotors of figure of
//       merit 0.3-0.8 (the GLMAV's is 0.13, the CoaX's upper rotor 0.29);
//   - channels the model does not explain: nrmse >= 0.9 on the estimation
//     or held-out data, where the channel's variation is above twice its
//     noise std (a channel that holds only noise has nothing to explain).
#pragma once

#include <map>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/parameters.h"

namespace coaxid {

inline constexpr double kUnexplainedNrmse = 0.9;

struct PlausibilityFinding {
  enum class Kind { kAtBound, kOutsidePhysicalRange, kUnexplainedChannel };
  Kind kind;
  std::string subject;  // a parameter (or "Ixx + Iyy - Izz"), or a channel
  double value = 0;     // the parameter's value, or the channel's nrmse
  // The bound met, or the physical range (one side may be +-inf); for a
  // channel, [0, kUnexplainedNrmse).
  double lower = 0, upper = 0;
  std::string where;    // channel findings: "estimation" or "held-out"
  std::string text;     // for people
};

struct PlausibilityVerdict {
  std::vector<PlausibilityFinding> findings;
  bool DescribesVehicle() const { return findings.empty(); }
  // One paragraph: "plausible: ..." or "the model does not describe this
  // vehicle: channels ...; parameters ...".
  std::string Summary() const;
  // {"describes_vehicle", "verdict", "findings": [{"kind", "subject",
  // "value", "range", "where", "text"}]}
  nlohmann::json ToJson() const;
};

// declared: the config's parameter set (known constants, bounds, units).
// estimates: the estimated parameters' values by name (names not in
// `declared`, such as linear_kf's Cz_alpha, are ignored). fit / validation:
// report.json "fit" and "validation" objects ({"<channel>": {"rms",
// "nrmse", ...}, "overall_nrmse"}); either may be null. noise_std: each
// channel's noise std where known (empty: judged by nrmse alone).
// undetermined: estimates the fit found the logs do not determine; their
// place at a bound is no finding (it is arbitrary), their value against the
// physical ranges is.
PlausibilityVerdict JudgePlausibility(const ParameterSet& declared,
                                      const std::map<std::string, double>& estimates,
                                      const nlohmann::json& fit, const nlohmann::json& validation,
                                      const std::map<std::string, double>& noise_std = {},
                                      const std::set<std::string>& undetermined = {});

// The estimated parameters of a report.json "parameters" object (entries
// with "estimated": true and a numeric value). Those the fit found
// undetermined (std null) only where they sit at or beyond a bound of
// `declared` (inertias pressed to 0.1 kg m^2 with the scale held: their
// physical range is judged), named in *undetermined; elsewhere their value
// is arbitrary and the report says so.
std::map<std::string, double> EstimatesOfReport(const nlohmann::json& parameters,
                                                const ParameterSet& declared,
                                                std::set<std::string>* undetermined = nullptr);

}  // namespace coaxid
