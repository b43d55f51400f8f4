// What an experiment design optimises: the precision of the parameters a
// user names, in relative terms (std / |value|), so that parameters of any
// unit weigh alike, as the fit's information M gives it (the bound a fit
// reports; output_error.h, PredictedPrecision).
//   D-optimal (Ds on the named subset): log det of their relative covariance,
//     the others estimated too (nuisance parameters);
//   A-optimal: the sum of their relative variances.
// Smaller is better for both.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "ident/output_error/output_error.h"

namespace coaxid {

struct DesignCriterion {
  enum class Kind { kD, kA };
  Kind kind = Kind::kD;
  std::vector<std::string> parameters;  // empty: every free parameter
  std::string Name() const { return kind == Kind::kD ? "D" : "A"; }
};

// The criterion on an information matrix (scaled coordinates, as in
// PredictedPrecision) and its gradient along directions G_k (d/dt of the
// criterion at M + t G_k). Works on the inverse of M regularised by
// 1e-12 of its trace, so a direction no experiment sees does not make it
// infinite.
class CriterionOnInformation {
 public:
  // Throws InputError when a named parameter is not free in `precision`
  // (held for the scale, or not estimated).
  CriterionOnInformation(const DesignCriterion& criterion, const PredictedPrecision& precision);
  double Value(const Eigen::MatrixXd& information_scaled) const;
  Eigen::VectorXd Gradient(const Eigen::MatrixXd& information_scaled,
                           const std::vector<Eigen::MatrixXd>& directions) const;
  const std::vector<int>& targets() const { return targets_; }

 private:
  Eigen::MatrixXd Inverse(const Eigen::MatrixXd& information_scaled) const;
  DesignCriterion criterion_;
  std::vector<int> targets_;   // positions among the free parameters
  Eigen::VectorXd relative_;   // scaled value of each free parameter (|value| / scale)
};

}  // namespace coaxid
