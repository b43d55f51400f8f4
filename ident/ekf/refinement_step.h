// Where a Gauss-Newton step of the filter's likelihood leads (ekf.h,
// "Refinement"), in two shapes that agree to first order and part on the
// ridges the logs leave:
//  - logarithmic: a parameter whose bounds keep its sign moves to
//    p exp(lambda dp / p), the others to p + lambda dp. Products and ratios
//    (the stabilizer bar's k_b d_u, d beta / Ixx) are straight lines in logs
//    and hyperbolas in values: a straight step along a hyperbola leaves it
//    (GLMAV with a bar, seed 8101: d_u 0.34 - 0.48 < 0).
//  - linear: p + lambda dp, and a parameter that would cross a bound is held
//    at it while the others move as the step's Gaussian N(p + lambda dp, P)
//    conditioned on that, so they stay on the ridge P describes (the
//    interference loss sigma0 at its lower bound 0 with alpha, the overall
//    thrust, moving to compensate; a clamp alone leaves the ridge).
// Both end within [lower, upper].
//
// Internal to ident/ekf: ekf.cc uses it.
#pragma once

#include <Eigen/Core>

namespace coaxid {

enum class RefinementStepShape { kLogarithmic, kLinear };

// p, step, lower, upper in the filter's scaled units; P the parameters'
// covariance at p (scaled).
Eigen::VectorXd SteppedParameters(const Eigen::VectorXd& p, const Eigen::VectorXd& step,
                                  double lambda, RefinementStepShape shape,
                                  const Eigen::MatrixXd& P, const Eigen::VectorXd& lower,
                                  const Eigen::VectorXd& upper);

}  // namespace coaxid
