#include "ident/ekf/rts_smoother.h"

#include <Eigen/Cholesky>
#include <glog/logging.h>

namespace coaxid {

void RtsSmoother::Reserve(int steps) {
  gains_.reserve(static_cast<size_t>(steps) * n_ * n_);
  d_packed_.reserve(static_cast<size_t>(steps) * n_ * (n_ + 1) / 2);
  offsets_.reserve(static_cast<size_t>(steps) * n_);
}

void RtsSmoother::Clear() {
  steps_ = 0;
  gains_.clear();
  d_packed_.clear();
  offsets_.clear();
}

bool RtsSmoother::AddTransition(const Eigen::VectorXd& x_filtered,
                                const Eigen::MatrixXd& P_filtered, const Eigen::MatrixXd& Phi,
                                const Eigen::VectorXd& x_predicted,
                                const Eigen::MatrixXd& P_predicted, std::string* error) {
  CHECK_EQ(x_filtered.size(), n_);
  CHECK_EQ(P_predicted.rows(), n_);
  const Eigen::LLT<Eigen::MatrixXd> llt(P_predicted);
  if (llt.info() != Eigen::Success) {
    *error = "predicted covariance not positive definite (smoother gain)";
    return false;
  }
  // C^T = P_pred^{-1} Phi P_filt (P's symmetric).
  const Eigen::MatrixXd PhiP = Phi * P_filtered;
  const Eigen::MatrixXd C = llt.solve(PhiP).transpose();
  Eigen::MatrixXd D = P_filtered - C * PhiP;
  D = 0.5 * (D + D.transpose());
  const Eigen::VectorXd a = x_filtered - C * x_predicted;
  if (!C.allFinite() || !D.allFinite()) {
    *error = "smoother gain not finite";
    return false;
  }
  gains_.insert(gains_.end(), C.data(), C.data() + C.size());
  for (int j = 0; j < n_; ++j) {
    for (int i = 0; i <= j; ++i) d_packed_.push_back(D(i, j));
  }
  offsets_.insert(offsets_.end(), a.data(), a.data() + n_);
  ++steps_;
  return true;
}

void RtsSmoother::Smooth(
    const Eigen::VectorXd& x_last, const Eigen::MatrixXd& P_last,
    const std::function<void(int, const Eigen::VectorXd&, const Eigen::MatrixXd&)>& visit) const {
  Eigen::VectorXd x = x_last;
  Eigen::MatrixXd P = P_last;
  visit(steps_, x, P);
  Eigen::MatrixXd D(n_, n_), CP(n_, n_);
  const size_t packed = static_cast<size_t>(n_) * (n_ + 1) / 2;
  for (int k = steps_ - 1; k >= 0; --k) {
    const Eigen::Map<const Eigen::MatrixXd> C(gains_.data() + static_cast<size_t>(k) * n_ * n_,
                                              n_, n_);
    const Eigen::Map<const Eigen::VectorXd> a(offsets_.data() + static_cast<size_t>(k) * n_, n_);
    const double* d = d_packed_.data() + k * packed;
    for (int j = 0; j < n_; ++j) {
      for (int i = 0; i <= j; ++i) D(i, j) = D(j, i) = *d++;
    }
    x = a + C * x;
    CP.noalias() = C * P;
    P = D;
    P.noalias() += CP * C.transpose();
    P = 0.5 * (P + P.transpose()).eval();
    visit(k, x, P);
  }
}

}  // namespace coaxid
