// The EKF's refinement to the maximum of its likelihood (ekf.h,
// "Refinement"; docs/ekf_refinement.md): Gauss-Newton steps carried by the
// frozen (covariance) pass, taken by further frozen passes while the
// likelihood rises.
//
// Internal to ident/ekf: ekf.cc uses it.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "ident/ekf/ekf.h"
#include "ident/ekf/pass.h"

namespace coaxid {

// Where lambda times a Gauss-Newton step leads: a parameter whose bounds
// keep its sign moves to p exp(lambda dp / p), the others to p + lambda dp,
// then within [lower, upper]. The same as the straight step to first order,
// but products and ratios (the stabilizer bar's k_b d_u, d beta / Ixx) are
// straight lines in logs and hyperbolas in values: a straight step along a
// hyperbola leaves it (GLMAV with a bar, seed 8101: d_u 0.34 - 0.48 < 0,
// clamped to 0, the likelihood down from 426397 to 69636; in logs the step
// was taken and the refinement reached the truth). Scaled units.
Eigen::VectorXd SteppedParameters(const Eigen::VectorXd& p, const Eigen::VectorXd& step,
                                  double lambda, const Eigen::VectorXd& lower,
                                  const Eigen::VectorXd& upper);

struct Refinement {
  Eigen::VectorXd p;  // the refined parameters (scaled)
  PassResult at_p;    // the frozen pass there (unsmoothed unless it is the start's)
  int steps = 0;
  double step_std_at_start = 0, step_std = 0;  // largest step in std, at the start and at p
  bool converged = true;
  std::string stop;  // why it stopped, in words
};

// From p (at: the frozen pass at p), while some parameter's step exceeds
// options.refine_tolerance_std of its std: the step, halved while the
// likelihood does not rise and it still exceeds the tolerance, each trial a
// frozen_pass; at most options.max_refinements steps. Not converged: the
// steps ran out, or a step above options.unconverged_step_std does not
// raise the likelihood.
Refinement Refine(const Eigen::VectorXd& p, const PassResult& at, const EkfOptions& options,
                  const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                  const std::function<PassResult(const Eigen::VectorXd&)>& frozen_pass);

// The parameters the step at p (of the frozen pass `at`) moves by more than
// `tolerance` std, as "k_b +5.5 std, d_u -4.2 std".
std::string LargeSteps(const Eigen::VectorXd& p, const PassResult& at, double tolerance,
                       const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                       const std::vector<std::string>& names);

}  // namespace coaxid
