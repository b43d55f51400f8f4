// What flight logs cannot determine, for the EKF: the scale of model.md
// decision 8 is ident/scale_gauge.h's; this finds undetermined directions in
// the data. With prior covariance P0 and final covariance P of the (scaled)
// parameters, the generalised eigenproblem P c = lambda P0 c gives the linear
// combinations c^T p whose variance the logs did not reduce (lambda near 1:
// no information); the parameter-space direction along which the estimate is
// free is v = P0 c. With every member of the scale group estimated, v matches
// the scale direction.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace coaxid {

struct UndeterminedDirection {
  double variance_ratio = 0;  // lambda: final / prior variance of c^T p
  Eigen::VectorXd direction;  // v = P0 c over the free parameters (scaled), unit norm, largest entry > 0
  // |cos| of the angle to the scale direction in scaled coordinates (NaN if none).
  double cos_to_scale = 0;
};

// Directions with lambda > threshold, largest lambda first. prior and
// posterior: covariances of the scaled free parameters. scale_scaled: the
// scale direction restricted to the free parameters, in scaled coordinates
// (empty: none).
std::vector<UndeterminedDirection> FindUndeterminedDirections(
    const Eigen::MatrixXd& prior, const Eigen::MatrixXd& posterior, double threshold,
    const Eigen::VectorXd& scale_scaled);

}  // namespace coaxid
