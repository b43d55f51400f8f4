// What flight logs cannot determine (model.md, decision 8), for the EKF.
//
// 1. The known scaling direction. Scaling d, gamma1, gamma2, Ixx, Iyy, Izz
//    (and any moment-type effect parameter) by one factor c leaves every
//    flight output unchanged: the moments scale by c and so do the inertias.
//    FindScaleDirection checks this on the model itself rather than trusting a
//    list: with v_i = d theta_i / d log c, the invariance means
//        sum_i v_i d[f; y_acc]/d theta_i = 0
//    at every state and input. v_i = theta_i on the six base parameters; the
//    enabled effects' share is solved by least squares over sample points
//    (a moment-type effect parameter gets v_e = theta_e, any other 0), and the
//    residual says whether the invariance holds.
// 2. Undetermined directions found in the data. With prior covariance P0 and
//    final covariance P of the (scaled) parameters, the generalised
//    eigenproblem P c = lambda P0 c gives the linear combinations c^T p whose
//    variance the logs did not reduce (lambda near 1: no information); the
//    parameter-space direction along which the estimate is free is v = P0 c.
//    With every member of the scale group estimated, v matches (1).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/input_hold.h"
#include "core/parameters.h"
#include "dynamics/state.h"
#include "dynamics/vehicle_model.h"

namespace coaxid {

struct ModelSample {
  State x;
  InputVector u;
};

struct ScaleDirection {
  bool exists = false;
  // Full theta size: v_i = d theta_i / d log c (0 outside the group).
  Eigen::VectorXd direction;
  std::vector<int> group;  // indices with v_i != 0, base parameters first
  // |sum_i v_i d[f; y]/d theta_i| relative to the size of its terms.
  double residual = 0;
};

// Candidates: every unknown base parameter and effect parameter (known
// constants are never part of it). samples: operating points (at least one).
ScaleDirection FindScaleDirection(const VehicleModel& model, const ParameterSet& parameters,
                                  const std::vector<ModelSample>& samples);

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

// A scale-free combination theta_a / theta_ref of the scale group, with its
// standard deviation from the (scaled) covariance of the free parameters by
// the delta method (fixed members contribute no variance).
struct ScaleRatio {
  std::string name;  // "Ixx/d"
  int numerator = -1, denominator = -1;  // theta indices
  double value = 0, std = 0;
};
// free_indices / scales: FreeParameters's; covariance: scaled (np x np).
// The reference is d when in the group, else the group's first member.
std::vector<ScaleRatio> ScaleRatios(const ScaleDirection& scale, const ParameterSet& parameters,
                                    const std::vector<int>& free_indices,
                                    const Eigen::VectorXd& scales,
                                    const Eigen::MatrixXd& covariance);

}  // namespace coaxid
