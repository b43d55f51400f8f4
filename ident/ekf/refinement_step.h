// Where a Gauss-Newton step of the filter's likelihood leads (ekf.h,
// "Refinement"): a parameter whose bounds keep its sign moves to
// p exp(lambda dp / p), the others to p + lambda dp, then within
// [lower, upper]. The same as the straight step to first order, but
// products and ratios (the stabilizer bar's k_b d_u, d beta / Ixx) are
// straight lines in logs and hyperbolas in values: a straight step along a
// hyperbola leaves it (GLMAV with a bar, seed 8101: d_u 0.34 - 0.48 < 0,
// clamped to 0, the likelihood down from 426397 to 69636; in logs the step
// was taken and the refinement reached the truth).
//
// Internal to ident/ekf: ekf.cc uses it.
#pragma once

#include <Eigen/Core>

namespace coaxid {

// p, step, lower, upper in the filter's scaled units.
Eigen::VectorXd SteppedParameters(const Eigen::VectorXd& p, const Eigen::VectorXd& step,
                                  double lambda, const Eigen::VectorXd& lower,
                                  const Eigen::VectorXd& upper);

}  // namespace coaxid
