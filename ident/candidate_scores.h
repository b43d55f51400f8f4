// Scores of the library's candidate effects against a fitted model
// (effects.md, step 3).
//
// For each effect not yet in the model: the effect is added with its
// parameters free and starting where the effect is absent (ground_effect's
// k_ge starts at 0 with bounds [0, 3]); its regressors along the data are the
// output Jacobians w.r.t. its parameters (model_jacobian.h), which say which
// channels it can reach; then the model with the effect is refitted jointly
// (every parameter free, the noise weights of the current fit held fixed) and
// the nested models are compared with the F-test
//     F = ((RSS0 - RSS1) / q) / (RSS1 / (N - P1)),   p = P(F(q, N - P1) > F),
// RSS the noise-weighted residual sum of squares over every output sample,
// q the effect's parameter count, P1 the free parameters with it.
// p-values are corrected for the candidates tried with Holm's step-down
// method (which controls the family-wise error rate like Bonferroni, less
// conservatively).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "dynamics/vehicle.h"
#include "ident/estimation_log.h"
#include "ident/output_error.h"

namespace coaxid {

struct CandidateScore {
  std::string effect, description;
  int round = 0;                      // loop round (1 = against the declared model)
  bool testable = false;              // some channel of these logs depends on it
  std::string why_not_testable;
  std::vector<std::string> channels;  // channels its regressors reach
  std::string reason;                 // the physical reason it would show in those channels
  int num_parameters = 0;
  double rss_before = 0, rss_after = 0;
  int num_residuals = 0, num_free_parameters = 0;
  double statistic = 0;               // F
  double p_value = 1;                 // uncorrected
  double p_corrected = 1;             // Holm over the candidates tried this round
  bool passes = false;
  ParameterSet parameters;            // the refit's estimates (testable only)
  IdentifiabilityReport identifiability;
  nlohmann::json ToJson() const;
};

// Noise-weighted residual sum of squares and its sample count.
double WeightedRss(const std::vector<EstimationLog>& logs,
                   const std::vector<Eigen::MatrixXd>& model, const NoiseWeights& noise,
                   int* count);

// The vehicle with `effect` added for scoring (parameters free, absent).
Vehicle CandidateVehicle(const Vehicle& vehicle, const std::string& effect);

// Scores every library effect not in `vehicle` (whose fit is `fit`, on `logs`).
// Sorted: passing first, then by p-value, then by statistic.
std::vector<CandidateScore> ScoreCandidates(const Vehicle& vehicle, const OutputErrorResult& fit,
                                            const std::vector<EstimationLog>& logs,
                                            const OutputErrorOptions& fit_options, double alpha,
                                            int round,
                                            const std::function<void(const std::string&)>& progress = nullptr);

}  // namespace coaxid
