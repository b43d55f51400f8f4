// The paper's Kalman parameter estimator (sect. 4, eqs. 66-70, 80-82): the
// parameter vector Theta = (beta, Cz_alpha, Cz_beta, gamma1, gamma2) is the
// state of a random walk (eq. 66, Q = 0 in the paper), observed through the
// linear balance model z_k = X_k Theta + v_k (eq. 67) with outputs
// (Z_bar, L, M, N) and R from the data (noise_covariance.h):
//
//   K_k     = P_{k-1} X_k^T [X_k P_{k-1} X_k^T + R]^{-1}                  (80)
//   Theta_k = Theta_{k-1} + K_k [z_k - X_k Theta_{k-1}]                    (81)
//   P_k     = (I - K_k X_k) P_{k-1} (I - K_k X_k)^T + K_k R K_k^T + Q      (82, Joseph form)
//
// (The paper prints eq. 82 as P - K X P + Q, the same in exact arithmetic;
// the Joseph form keeps P symmetric positive definite in floating point,
// STYLE.md item 7.) The gain is computed with a Cholesky solve, never an
// explicit inverse. Internally the filter runs on Theta / scale with the
// outputs divided by their noise std, so every number is of order one.
//
// One update per sample (row); a missing output is skipped (its row of X_k
// is dropped, exactly); a row with no output at all is counted and skipped.
// The prior is diffuse: Theta_0 the config's nominal values, P_0 =
// diag((prior_std * scale)^2) with prior_std large.
#pragma once

#include <string>
#include <vector>

#include "ident/baseline/linear_balance_model.h"

namespace coaxid {

struct LinearKfOptions {
  ThetaVector initial = ThetaVector::Zero();  // Theta_0
  ThetaVector scale = ThetaVector::Ones();  // typical magnitude of each parameter (units of Theta)
  // Diffuse prior: P_0 = diag((prior_std * scale)^2). Infinite: no prior
  // (batch route only; the filter needs a finite P_0). The covariance form
  // loses about eps * prior_std^2 * (per-sample information) of P to
  // round-off on the first updates, so a prior far more diffuse than needed
  // costs accuracy: 1e3 scales weighs ~1e-9 of the data's information here.
  double prior_std = 1e3;
  // Q = process_noise * diag(scale^2) added at every update (eq. 66); 0 as
  // the paper. Dimensionless: the variance of the per-sample random walk of
  // Theta_i / scale_i.
  double process_noise = 0;
  int history_stride = 1;  // keep every n-th update in the history (and the last)
  bool IsValid(std::string* why) const;
};

// Fig. 11: the estimate and trace(P) after each kept update.
struct LinearKfHistory {
  std::vector<int> data_index;  // which data set
  std::vector<int> row;         // row of that data set
  std::vector<double> t;        // its time [s]
  std::vector<ThetaVector> estimate;
  // trace of P in scaled units, sum_i P_ii / scale_i^2 (dimensionless; the
  // physical trace would mix units and be dominated by one parameter).
  std::vector<double> trace_scaled;
};

struct LinearKfSummary {
  ThetaVector estimate = ThetaVector::Zero();
  ThetaMatrix covariance = ThetaMatrix::Zero();  // P at the end
  LinearKfHistory history;
  int updates = 0;       // rows with at least one output
  int skipped_rows = 0;  // rows with no output
  bool usable = false;
  std::string message;  // why not usable
  bool IsSolutionUsable() const { return usable; }
};

// Runs the filter over the data sets in order (eqs. 80-82).
LinearKfSummary RunLinearKf(const LinearBalanceModel& model,
                            const std::vector<WeightedBalanceData>& data,
                            const LinearKfOptions& options);

// The second route: the weighted least-squares solution of the same linear
// model and prior, min sum_k sum_c (z_kc - X_kc Theta)^2 / R_c
// + sum_i (Theta_i - Theta0_i)^2 / (prior_std scale_i)^2, by blocked
// Householder QR of the whitened, stacked rows (no normal equations). With
// Q = 0 the filter's final estimate and P equal this solution and its
// covariance (exactly, in exact arithmetic).
struct BatchLeastSquaresSummary {
  ThetaVector estimate = ThetaVector::Zero();
  ThetaMatrix covariance = ThetaMatrix::Zero();
  double weighted_rss = 0;  // sum of squared whitened residuals (prior rows included)
  int observations = 0;     // scalar outputs used
  bool usable = false;
  std::string message;
};
BatchLeastSquaresSummary SolveBatchLeastSquares(const LinearBalanceModel& model,
                                                const std::vector<WeightedBalanceData>& data,
                                                const LinearKfOptions& options);

}  // namespace coaxid
