// Rauch-Tung-Striebel fixed-interval smoother for a filter that runs
//   predict:  x_{k+1|k} = phi(x_{k|k}),  P_{k+1|k} = Phi_k P_{k|k} Phi_k^T + Q_k,
//   update:   x_{k+1|k+1}, P_{k+1|k+1}.
// The backward pass (Rauch, Tung and Striebel 1965):
//   C_k     = P_{k|k} Phi_k^T P_{k+1|k}^{-1}                 (smoother gain)
//   x_{k|N} = x_{k|k} + C_k (x_{k+1|N} - x_{k+1|k})
//   P_{k|N} = P_{k|k} + C_k (P_{k+1|N} - P_{k+1|k}) C_k^T
// The gain is computed in the forward pass from the Cholesky factor of
// P_{k+1|k} (never an explicit inverse; STYLE.md, item 7), and the covariance
// recursion is kept in the form
//   P_{k|N} = D_k + C_k P_{k+1|N} C_k^T,   D_k = P_{k|k} - C_k Phi_k P_{k|k} (>= 0),
// a sum of two positive semi-definite terms, symmetrised at every step.
//
// Storage per step: C_k (n x n), D_k (n(n+1)/2, packed) and
// a_k = x_{k|k} - C_k x_{k+1|k} (n), so that x_{k|N} = a_k + C_k x_{k+1|N}:
// (1.5 n^2 + 1.5 n) doubles, 7.2 kB at n = 24, 86 MB for a 60 s log at 200 Hz:
// the EKF keeps one block of steps at a time (ekf/pass.h).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace coaxid {

class RtsSmoother {
 public:
  explicit RtsSmoother(int n) : n_(n) {}
  void Reserve(int steps);
  int size() const { return steps_; }
  int dimension() const { return n_; }

  // The transition from step k (filtered x_{k|k}, P_{k|k}) to step k+1
  // (predicted x_{k+1|k}, P_{k+1|k}) with transition matrix Phi_k. Returns
  // false with *error set if P_{k+1|k} is not positive definite.
  bool AddTransition(const Eigen::VectorXd& x_filtered, const Eigen::MatrixXd& P_filtered,
                     const Eigen::MatrixXd& Phi, const Eigen::VectorXd& x_predicted,
                     const Eigen::MatrixXd& P_predicted, std::string* error);

  // Backward pass from the last filtered estimate (step size()). Calls
  // visit(k, x_{k|N}, P_{k|N}) for k = size(), size() - 1, ..., 0.
  void Smooth(const Eigen::VectorXd& x_last, const Eigen::MatrixXd& P_last,
              const std::function<void(int, const Eigen::VectorXd&, const Eigen::MatrixXd&)>&
                  visit) const;

  void Clear();

 private:
  int n_;
  int steps_ = 0;
  // Step k's C_k (n x n, column-major), D_k (upper triangle, column by column)
  // and a_k, stored contiguously.
  std::vector<double> gains_, d_packed_, offsets_;
};

}  // namespace coaxid
