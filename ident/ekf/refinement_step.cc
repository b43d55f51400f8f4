#include "ident/ekf/refinement_step.h"

#include <cmath>

namespace coaxid {

Eigen::VectorXd SteppedParameters(const Eigen::VectorXd& p, const Eigen::VectorXd& step,
                                  double lambda, const Eigen::VectorXd& lower,
                                  const Eigen::VectorXd& upper) {
  Eigen::VectorXd to = p + lambda * step;
  for (int k = 0; k < p.size(); ++k) {
    const bool keeps_sign = (lower[k] >= 0 && p[k] > 0) || (upper[k] <= 0 && p[k] < 0);
    if (keeps_sign) to[k] = p[k] * std::exp(lambda * step[k] / p[k]);
  }
  return to.cwiseMax(lower).cwiseMin(upper);
}

}  // namespace coaxid
