#include "ident/ekf/identifiability.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>
#include <glog/logging.h>

namespace coaxid {

std::vector<UndeterminedDirection> FindUndeterminedDirections(
    const Eigen::MatrixXd& prior, const Eigen::MatrixXd& posterior, double threshold,
    const Eigen::VectorXd& scale_scaled) {
  std::vector<UndeterminedDirection> out;
  const int np = static_cast<int>(prior.rows());
  if (np == 0) return out;
  const Eigen::LLT<Eigen::MatrixXd> llt(prior);
  CHECK(llt.info() == Eigen::Success) << "prior parameter covariance not positive definite";
  const Eigen::MatrixXd L = llt.matrixL();
  // M = L^{-1} P L^{-T}: symmetric, eigenvalues = the generalised ones.
  Eigen::MatrixXd M = L.triangularView<Eigen::Lower>().solve(posterior);
  M = L.triangularView<Eigen::Lower>().solve(M.transpose().eval());
  M = 0.5 * (M + M.transpose()).eval();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(M);
  for (int j = np - 1; j >= 0; --j) {
    const double lambda = eig.eigenvalues()[j];
    if (!(lambda > threshold)) break;
    UndeterminedDirection d;
    d.variance_ratio = lambda;
    d.direction = L * eig.eigenvectors().col(j);
    d.direction.normalize();
    int largest;
    d.direction.cwiseAbs().maxCoeff(&largest);
    if (d.direction[largest] < 0) d.direction = -d.direction;
    d.cos_to_scale = std::numeric_limits<double>::quiet_NaN();
    if (scale_scaled.size() == np && scale_scaled.norm() > 0) {
      d.cos_to_scale = std::fabs(d.direction.dot(scale_scaled)) / scale_scaled.norm();
    }
    out.push_back(d);
  }
  return out;
}

}  // namespace coaxid
