// The Fisher information of an output-error fit's free parameters with the
// multiple-shooting segment states marginalised out, and the correction of
// its Cramér-Rao bounds for coloured (autocorrelated) output residuals.
//
// Information: with J the residual Jacobian over [segment states s | theta]
// (scaled coordinates) and H = J^T J, the information on theta alone is the
// Schur complement M = H_tt - H_ts H_ss^-1 H_st. H is accumulated block by
// block from each residual block's Jacobian (the segments' cached
// simulations at the solution serve them): H_ss is block tridiagonal, so
// the elimination is a sparse factorisation of a small matrix.
//
// Coloured residuals (Morelli & Klein, "Accuracy of aerodynamic model
// parameters estimated from flight test data", J. Guidance 20(1), 1997):
// the white-noise bound M^-1 is optimistic when the output residuals are
// autocorrelated. With G_k the sensitivities of the weighted output
// residuals of sample k to theta (states marginalised: G = J_t - J_s H_ss^-1
// H_st) and Rvv(tau) the sample cross-correlation matrix of the weighted
// residual vectors at lag tau,
//   Cov = M^-1 [ sum_k sum_j G_k^T Rvv(k - j) G_j ] M^-1,
// with the lag sum truncated where the residual autocorrelation has died out
// (the last lag before every channel's autocorrelation has entered the
// +-2/sqrt(N) band of white noise). Residuals of
// balance logs (one per hold) and continuity residuals enter as white.
#pragma once

#include <vector>

#include <ceres/ceres.h>
#include <Eigen/Core>

#include "ident/estimation_log.h"
#include "ident/output_error/costs.h"

namespace coaxid {

// One log's residual blocks at the solution.
struct LogResidualBlocks {
  const EstimationLog* log = nullptr;
  std::vector<const FlightSegmentCost*> segments;  // flight: in time order
  // The same segments as Ceres saw them (CompressedSegmentCost: the same
  // J^T J, kept at the solution), used when the flight rows are not kept.
  std::vector<const ceres::CostFunction*> compressed;
  std::vector<const double*> segment_states;       // their start states (12 each)
  std::vector<int> held_states;                    // coordinates held constant on the first one
  std::vector<const BalanceRowsCost*> balance;
};

struct OutputErrorInformation {
  Eigen::MatrixXd information;  // P x P, in scaled coordinates (value / scale)
  // The balance logs' share of it (rows with measurement noise and no
  // segment states).
  Eigen::MatrixXd balance_information;
  // Per log (empty for balance logs), kept when asked for the correction.
  struct FlightRows {
    int num_channels = 0;
    Eigen::MatrixXd sensitivities;  // (rows x channels) x P, row k * channels + c: G_k
    Eigen::MatrixXd residuals;      // rows x channels, weighted; 0 where no value
    Eigen::MatrixXd present;        // rows x channels, 1 where a value, 0 where none
  };
  std::vector<FlightRows> flight;
};

// Throws ComputationError if a residual block cannot be evaluated.
OutputErrorInformation ComputeOutputErrorInformation(const std::vector<LogResidualBlocks>& logs,
                                                     const double* theta_scaled, int P,
                                                     bool keep_flight_rows);

// The information in the coordinates theta'_k = factors_k theta_k, for a
// model whose outputs at theta' equal those at theta (a move along an
// invariance): Jacobian columns divided by the factors.
void RescaleParameters(const Eigen::VectorXd& factors, OutputErrorInformation* info);

// The information with parameter k held fixed: its row and column (and its
// column of the flight sensitivities) removed.
void DropParameter(int k, OutputErrorInformation* info);

struct ColouredResidualCorrection {
  Eigen::MatrixXd covariance_scaled;  // the corrected covariance, scaled coordinates
  std::vector<int> lags;              // per flight log, the truncation lag [samples]
};

// covariance_scaled: the white-noise bound (the pseudo-inverse of the
// information on the identifiable subspace). max_lag caps the lag sum.
ColouredResidualCorrection CorrectForColouredResiduals(const OutputErrorInformation& info,
                                                       const Eigen::MatrixXd& covariance_scaled,
                                                       int max_lag);

}  // namespace coaxid
