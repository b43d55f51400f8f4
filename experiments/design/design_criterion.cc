#include "experiments/design/design_criterion.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "core/errors.h"

namespace coaxid {

CriterionOnInformation::CriterionOnInformation(const DesignCriterion& criterion,
                                               const PredictedPrecision& precision)
    : criterion_(criterion) {
  const int P = static_cast<int>(precision.names.size());
  relative_.resize(P);
  for (int k = 0; k < P; ++k) {
    relative_[k] = std::fabs(precision.parameters.Value(precision.names[k])) / precision.scales[k];
  }
  if (criterion.parameters.empty()) {
    for (int k = 0; k < P; ++k) targets_.push_back(k);
  }
  for (const std::string& name : criterion.parameters) {
    auto it = std::find(precision.names.begin(), precision.names.end(), name);
    if (it == precision.names.end()) {
      std::string why = precision.parameters.Has(name)
                            ? (name == precision.gauge.held
                                   ? "is held for the scale (flight logs alone fix only ratios, "
                                     "model.md decision 8): add a balance scenario or name "
                                     "another parameter"
                                   : "is not estimated in the config")
                            : "is not a parameter of this vehicle";
      throw InputError("design parameter '" + name + "' " + why);
    }
    const int k = static_cast<int>(it - precision.names.begin());
    if (!(relative_[k] > 0)) {
      throw InputError("design parameter '" + name +
                       "' is 0 in the config: its relative precision is undefined");
    }
    targets_.push_back(k);
  }
}

Eigen::MatrixXd CriterionOnInformation::Inverse(const Eigen::MatrixXd& M) const {
  const int P = static_cast<int>(M.rows());
  const double ridge = 1e-12 * std::max(M.trace(), 1e-300);
  const Eigen::MatrixXd regularised = M + ridge * Eigen::MatrixXd::Identity(P, P);
  return regularised.ldlt().solve(Eigen::MatrixXd::Identity(P, P));
}

double CriterionOnInformation::Value(const Eigen::MatrixXd& M) const {
  // An information that is not positive definite (a local model pushed too
  // far) is no experiment at all.
  const int P = static_cast<int>(M.rows());
  const Eigen::LLT<Eigen::MatrixXd> llt(
      M + 1e-12 * std::max(M.trace(), 1e-300) * Eigen::MatrixXd::Identity(P, P));
  if (llt.info() != Eigen::Success || !M.allFinite()) {
    return std::numeric_limits<double>::infinity();
  }
  const Eigen::MatrixXd C = Inverse(M);
  const int T = static_cast<int>(targets_.size());
  Eigen::MatrixXd C_T(T, T);
  for (int a = 0; a < T; ++a) {
    for (int b = 0; b < T; ++b) {
      C_T(a, b) = C(targets_[a], targets_[b]) / (relative_[targets_[a]] * relative_[targets_[b]]);
    }
  }
  if (criterion_.kind == DesignCriterion::Kind::kA) return C_T.trace();
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(C_T);
  double log_det = 0;
  for (int a = 0; a < T; ++a) log_det += std::log(std::max(ldlt.vectorD()[a], 1e-300));
  return log_det;
}

Eigen::VectorXd CriterionOnInformation::Gradient(const Eigen::MatrixXd& M,
                                                 const std::vector<Eigen::MatrixXd>& directions) const {
  // d C / dt = -C G C. D: d log det C_T = tr(C_T^-1 dC_T); A: tr(dC_T) (relative).
  const Eigen::MatrixXd C = Inverse(M);
  const int T = static_cast<int>(targets_.size()), P = static_cast<int>(M.rows());
  Eigen::MatrixXd select = Eigen::MatrixXd::Zero(P, T);  // columns: e_target / relative
  for (int a = 0; a < T; ++a) select(targets_[a], a) = 1.0 / relative_[targets_[a]];
  const Eigen::MatrixXd CS = C * select;  // P x T
  Eigen::MatrixXd weight;                 // T x T: C_T^-1 for D, I for A
  if (criterion_.kind == DesignCriterion::Kind::kD) {
    weight = (select.transpose() * C * select).ldlt().solve(Eigen::MatrixXd::Identity(T, T));
  } else {
    weight = Eigen::MatrixXd::Identity(T, T);
  }
  Eigen::VectorXd g(directions.size());
  for (size_t k = 0; k < directions.size(); ++k) {
    g[k] = -(weight * (CS.transpose() * directions[k] * CS)).trace();
  }
  return g;
}

}  // namespace coaxid
