#include "dynamics/rk4_stability.h"

#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

namespace coaxid {

double ScaledGershgorinBound(const Eigen::MatrixXd& A, const Eigen::VectorXd& scales) {
  // A NaN anywhere makes the bound NaN (so no test passes on it).
  if (scales.size() == 0) return A.cwiseAbs().rowwise().sum().maxCoeff<Eigen::PropagateNaN>();
  // Row i of D A D^-1 sums d_i |A_ij| / d_j: one product with 1 / d.
  return (A.cwiseAbs() * scales.cwiseInverse())
      .cwiseProduct(scales)
      .maxCoeff<Eigen::PropagateNaN>();
}

Eigen::VectorXd BalancingScales(const Eigen::MatrixXd& A) {
  const int n = static_cast<int>(A.rows());
  Eigen::VectorXd d = Eigen::VectorXd::Ones(n);
  constexpr int kMaxSweeps = 10;
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    bool moved = false;
    for (int i = 0; i < n; ++i) {
      // Off-diagonal sums of row i and column i of D A D^-1; scaling d_i by
      // f multiplies the row's by f and divides the column's by f.
      double row = 0, column = 0;
      for (int j = 0; j < n; ++j) {
        if (j == i) continue;
        row += std::fabs(A(i, j)) * d[i] / d[j];
        column += std::fabs(A(j, i)) * d[j] / d[i];
      }
      if (!(row > 0 && column > 0)) continue;  // nothing to balance against
      const double f = std::sqrt(column / row);
      // Only a step that shrinks row + column by 5 % or more (as gebal).
      if (2 * std::sqrt(row * column) >= 0.95 * (row + column)) continue;
      d[i] *= f;
      moved = true;
    }
    if (!moved) break;
  }
  return d;
}

double SpectralRadius(const Eigen::MatrixXd& A) {
  if (!A.allFinite()) return std::numeric_limits<double>::infinity();
  const Eigen::EigenSolver<Eigen::MatrixXd> eigen(A, /*computeEigenvectors=*/false);
  if (eigen.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  return eigen.eigenvalues().cwiseAbs().maxCoeff();
}

bool Rk4StabilityTest::Stable(double h, const Eigen::MatrixXd& A) {
  // A balancing made for another size (a test's matrices) does not apply.
  if (scales_.size() != A.rows()) scales_.resize(0);
  if (h * ScaledGershgorinBound(A, scales_) <= limit_) {
    ++by_row_sums_;
    return true;
  }
  scales_ = BalancingScales(A);
  if (h * ScaledGershgorinBound(A, scales_) <= limit_) {
    ++by_row_sums_;
    return true;
  }
  ++by_eigenvalues_;
  return h * SpectralRadius(A) <= limit_;
}

}  // namespace coaxid
