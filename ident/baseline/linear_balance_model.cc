#include "ident/baseline/linear_balance_model.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>

#include "dynamics/interference_loss.h"

namespace coaxid {
namespace {

// Cell index and fraction along one grid axis, as InterferenceLossFromTable
// locates them: clamped to the edges outside the grid.
void Locate(const std::vector<double>& grid, double w, int* cell, double* fraction) {
  const int n = static_cast<int>(grid.size());
  if (w <= grid.front()) {
    *cell = 0;
    *fraction = 0;
    return;
  }
  if (w >= grid.back()) {
    *cell = n - 2;
    *fraction = 1;
    return;
  }
  int k = static_cast<int>(std::upper_bound(grid.begin(), grid.end(), w) - grid.begin()) - 1;
  k = std::clamp(k, 0, n - 2);
  *cell = k;
  *fraction = (w - grid[k]) / (grid[k + 1] - grid[k]);
}

}  // namespace

const char* ThetaName(int index) {
  static const char* const kNames[kNumTheta] = {"beta", "Cz_alpha", "Cz_beta", "gamma1", "gamma2"};
  CHECK(index >= 0 && index < kNumTheta) << "Theta index " << index;
  return kNames[index];
}

double LinearBalanceModel::Sigma(const InputVector& u) const {
  if (sigma.empty()) return 1.0;
  return InterferenceLossFromTable(sigma, u[0], u[1]);
}

LinearizedLoads LinearBalanceModel::Linearize(const InputVector& u) const {
  const double w1 = u[0] * u[0];
  const double w2 = u[1] * u[1];
  const double cx = std::cos(u[2]), sx = std::sin(u[2]);
  const double cy = std::cos(u[3]), sy = std::sin(u[3]);
  const double s = Sigma(u);
  LinearizedLoads out;
  out.sigma = s;
  BalanceRegressor& X = out.X;
  X.setZero();
  X(kLoadX, kThetaBeta) = -sy * cx * w2;                     // X11
  X(kLoadY, kThetaBeta) = -sx * w2;                          // X21
  X(kLoadZ, kThetaBeta) = s * cy * cx * w2;                  // X31
  X(kLoadZ, kThetaCzAlpha) = -s * area_ratio * w1;           // X32
  X(kLoadZ, kThetaCzBeta) = -s * area_ratio * cy * cx * w2;  // X33
  X(kLoadL, kThetaBeta) = -d * sx * w2;                      // X41
  X(kLoadM, kThetaBeta) = d * sy * cx * w2;                  // X51
  X(kLoadN, kThetaGamma1) = w1;                              // X64
  X(kLoadN, kThetaGamma2) = w2;                              // X65
  out.offset.fill(0.0);
  out.offset[kLoadZ] = s * alpha * w1;  // Z_bar = Z - sigma alpha w1 (eq. 69)
  return out;
}

LoadVector LinearBalanceModel::Predict(const InputVector& u, const ThetaVector& theta) const {
  const LinearizedLoads lin = Linearize(u);
  const Eigen::Matrix<double, kNumLoadChannels, 1> loads = lin.X * theta;
  LoadVector out;
  for (int c = 0; c < kNumLoadChannels; ++c) out[c] = loads[c] + lin.offset[c];
  return out;
}

SigmaCellWeights SigmaWeights(const SigmaTable& table, double omega1, double omega2) {
  CHECK_GE(table.omega1.size(), 2u);
  CHECK_GE(table.omega2.size(), 2u);
  int i, j;
  double a, b;
  Locate(table.omega1, omega1, &i, &a);
  Locate(table.omega2, omega2, &j, &b);
  const int n2 = static_cast<int>(table.omega2.size());
  SigmaCellWeights w;
  w.cell = {i * n2 + j, i * n2 + j + 1, (i + 1) * n2 + j, (i + 1) * n2 + j + 1};
  w.weight = {(1 - a) * (1 - b), (1 - a) * b, a * (1 - b), a * b};
  return w;
}

}  // namespace coaxid
