// Standard deviations of the Kalman estimates that include the thrust map's
// uncertainty. The filter (as in the paper) treats alpha and the sigma map as
// known, so its P is conditional on them; but Z_bar = Z - sigma alpha w1
// depends on both, and the estimate of Cz_alpha moves by d(alpha)/k (k =
// S_s/S_prop ~ 0.014 here): an error of alpha within its own std shifts
// Cz_alpha by several of the filter's stds. This file propagates, to first
// order, the noise of every sample through the whole chain (single-rotor
// holds -> alpha, beta -> sigma map -> Z_bar and X_k -> Theta):
//
//   Theta = A^-1 b,  A = sum X^T R^-1 X (+ prior),  b = sum X^T R^-1 z_bar,
//   dTheta/dq = A^-1 (db/dq - dA/dq Theta)        for q = alpha, each table cell,
//
// with the table cells' and alpha's derivatives with respect to each hold's
// mean Z from thrust_map.h. A sample's noise then acts directly (the filter's
// P) and through its hold's mean (the map), and
//
//   Cov = P + sum_h [u_h m_h^T + m_h u_h^T + (R_Z / n_h) m_h m_h^T],
//   u_h = A^-1 X_Z(h)^T,  m_h = d(Theta, alpha) / d(mean Z of hold h),
//
// the cross terms coming from the same samples entering both routes. The
// result covers (Theta, alpha) jointly, so that ratios such as Cz_alpha /
// alpha get their std with the correlation. It is exact for the Q = 0
// (batch) solution to first order in the noise.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "ident/baseline/linear_balance_model.h"
#include "ident/baseline/linear_kf.h"
#include "ident/baseline/thrust_map.h"

namespace coaxid {

// (Theta, alpha): indices 0..4 as ThetaIndex, then alpha.
inline constexpr int kPsiAlpha = kNumTheta;
inline constexpr int kNumPsi = kNumTheta + 1;
using PsiVector = Eigen::Matrix<double, kNumPsi, 1>;
using PsiMatrix = Eigen::Matrix<double, kNumPsi, kNumPsi>;

// data[i] must be the data set the map's MapHold::data_index i refers to
// (the same list, in the same order, FitThrustMap was given), model.sigma the
// map's table and model.alpha the map's alpha. filter_covariance is the
// filter's P (the direct part).
PsiMatrix PropagateMapUncertainty(const LinearBalanceModel& model,
                                  const std::vector<WeightedBalanceData>& data,
                                  const ThrustMap& map, const ThetaVector& theta,
                                  const ThetaMatrix& filter_covariance,
                                  const LinearKfOptions& options);

}  // namespace coaxid
