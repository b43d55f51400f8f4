#include "ident/ekf/refinement_step.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <vector>

namespace coaxid {

Eigen::VectorXd SteppedParameters(const Eigen::VectorXd& p, const Eigen::VectorXd& step,
                                  double lambda, RefinementStepShape shape,
                                  const Eigen::MatrixXd& P, const Eigen::VectorXd& lower,
                                  const Eigen::VectorXd& upper) {
  const int n = static_cast<int>(p.size());
  Eigen::VectorXd to = p + lambda * step;
  if (shape == RefinementStepShape::kLogarithmic) {
    for (int k = 0; k < n; ++k) {
      const bool keeps_sign = (lower[k] >= 0 && p[k] > 0) || (upper[k] <= 0 && p[k] < 0);
      if (keeps_sign) to[k] = p[k] * std::exp(lambda * step[k] / p[k]);
    }
    return to.cwiseMax(lower).cwiseMin(upper);
  }
  // Linear: hold the parameters beyond a bound at it, condition the others
  // (x_F + P_FA P_AA^-1 (b_A - x_A)), until none is beyond.
  const Eigen::VectorXd free_move = to;
  std::vector<int> held;
  std::vector<char> is_held(n, 0);
  for (int round = 0; round <= n; ++round) {
    bool added = false;
    for (int k = 0; k < n; ++k) {
      if (!is_held[k] && (to[k] < lower[k] || to[k] > upper[k])) {
        is_held[k] = 1;
        held.push_back(k);
        added = true;
      }
    }
    if (!added) break;
    const int a = static_cast<int>(held.size());
    Eigen::MatrixXd P_aa(a, a), P_na(n, a);
    Eigen::VectorXd shift(a);
    for (int i = 0; i < a; ++i) {
      const int k = held[i];
      shift[i] = std::clamp(free_move[k], lower[k], upper[k]) - free_move[k];
      for (int j = 0; j < a; ++j) P_aa(i, j) = P(k, held[j]);
      P_na.col(i) = P.col(k);
    }
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(P_aa);
    to = free_move + P_na * ldlt.solve(shift);
    for (int k : held) to[k] = std::clamp(free_move[k], lower[k], upper[k]);
  }
  return to.cwiseMax(lower).cwiseMin(upper);
}

}  // namespace coaxid
