// The paper's linearised balance model (sect. 4, eqs. 61-70): the one place
// the regressors X_k of eq. 70 are written. The Kalman filter, the batch
// least-squares route, the excitation check and the reconstruction all call
// LinearBalanceModel::Linearize; nothing else computes a regressor.
//
// On the balance (u = v = w = 0, no wind, model.md decision 5), with
// Cz_alpha = Cz alpha and Cz_beta = Cz beta (eqs. 64-65), w1 = omega1^2,
// w2 = omega2^2, c = cos(delta_cx) cos(delta_cy), k = S_s / S_prop:
//
//   X     = -beta sin(delta_cy) cos(delta_cx) w2                          (61)
//   Y     = -beta sin(delta_cx) w2                                        (62)
//   Z     = sigma alpha w1 + sigma beta c w2 - k sigma (Cz_alpha w1 + Cz_beta c w2)   (63)
//   L     = -d beta sin(delta_cx) w2,  M = d beta sin(delta_cy) cos(delta_cx) w2        (57-58)
//   N     = gamma1 w1 + gamma2 w2                                         (59)
//
// so that (X, Y, Z_bar, L, M, N) = X_k Theta with Z_bar = Z - sigma alpha w1
// (eq. 69) and Theta = (beta, Cz_alpha, Cz_beta, gamma1, gamma2) (eq. 68).
// alpha comes from the thrust map, sigma from the map of the same logs, d from
// the config (model.md decision 6). Columns X31 = sigma c w2 and
// X33 = -k sigma c w2 are exactly collinear: beta and Cz_beta separate only
// through L and M, that is through d.
#pragma once

#include <Eigen/Core>
#include <array>

#include "core/input_hold.h"
#include "core/vehicle_config.h"
#include "ident/baseline/balance_holds.h"

namespace coaxid {

// The parameter vector Theta of eq. 68, in this order.
enum ThetaIndex : int {
  kThetaBeta,
  kThetaCzAlpha,
  kThetaCzBeta,
  kThetaGamma1,
  kThetaGamma2,
  kNumTheta
};
// "beta", "Cz_alpha", "Cz_beta", "gamma1", "gamma2".
const char* ThetaName(int index);

using ThetaVector = Eigen::Matrix<double, kNumTheta, 1>;
using ThetaMatrix = Eigen::Matrix<double, kNumTheta, kNumTheta>;
// X_k of eq. 69: rows X, Y, Z_bar, L, M, N (LoadChannel order), columns Theta.
using BalanceRegressor = Eigen::Matrix<double, kNumLoadChannels, kNumTheta>;

// The outputs the estimation uses (eqs. 69-70 with model.md decision 6):
// Z_bar, L, M, N. X and Y only validate (paper, sect. 3 and 5).
inline constexpr int kNumEstimationChannels = 4;
inline constexpr std::array<int, kNumEstimationChannels> kEstimationChannels = {kLoadZ, kLoadL,
                                                                                kLoadM, kLoadN};

// The model at one input: loads = X Theta + offset.
struct LinearizedLoads {
  BalanceRegressor X;  // eq. 70
  LoadVector offset;   // sigma alpha w1 on Z (Z_bar = Z - offset), zero elsewhere
  double sigma = 1;    // the interference loss used
};

struct LinearBalanceModel {
  double alpha = 0;       // upper-rotor thrust coefficient from the thrust map [N s^2]
  double d = 0;           // G to lower-rotor hub, from the config [m]
  double area_ratio = 0;  // k = S_s / S_prop = D^2 / R^2 (eq. 26) [-]
  SigmaTable sigma;       // interference-loss map; empty: sigma = 1 everywhere

  // sigma(omega1, omega2) from the map, bilinear (dynamics/interference_loss.h).
  double Sigma(const InputVector& u) const;
  // Eq. 70 at input u.
  LinearizedLoads Linearize(const InputVector& u) const;
  // Model loads X, Y, Z, L, M, N at input u.
  LoadVector Predict(const InputVector& u, const ThetaVector& theta) const;
};

// A balance data set with the measurement-noise variances of its load
// channels (R diagonal, eqs. 83-84), as the filter and the batch route read it.
struct WeightedBalanceData {
  const BalanceData* data = nullptr;
  LoadVector variance{};  // [N^2] for X, Y, Z; [(N m)^2] for L, M, N; > 0 where used
};

// Bilinear weights of a sigma table at (omega1, omega2): sigma = sum of
// weight[i] * table.sigma[cell[i]], the same interpolation (and clamping) as
// InterferenceLossFromTable. Used to propagate the map's uncertainty.
struct SigmaCellWeights {
  std::array<int, 4> cell{};
  std::array<double, 4> weight{};
};
SigmaCellWeights SigmaWeights(const SigmaTable& table, double omega1, double omega2);

}  // namespace coaxid
