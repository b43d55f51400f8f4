// Whether one classic RK4 step of h is stable on the linear system dS/dt = A S
// (the sensitivities' step a hold, Simulator::StepSensitivities): every
// eigenvalue lambda of A with h |lambda| inside the step's stability region
// (-2.79 on the real axis, +-2.83 on the imaginary one), tested as
// h rho(A) <= limit with rho the spectral radius.
//
// rho is bounded cheaply first. Any diagonal D > 0 leaves the eigenvalues of
// D A D^-1 those of A, so the largest absolute row sum of D A D^-1
// (Gershgorin) bounds rho for every D. With D = I the bound depends on the
// states' units: a vehicle's A mixes rad, m/s and rad/s, and its row sums
// ran 8 to 100 times above rho (measured, confusion study seed 21313, a
// 10 ms hold: 338 k of 1.79 M steps over the limit by the unscaled row sums,
// 2 of them with h rho above 0.25, none above 2; each went to the
// variational equations, 9 right-hand sides with Jacobians a step, and the
// run took 32.7 s against 21.0 s with rho itself deciding). So the test
// keeps a balancing D (Osborne's iteration, as LAPACK's gebal: each state's
// row and column made equal in size), made from the first matrix that needs
// it and kept while it serves; where the balanced bound still exceeds the
// limit, rho itself (the eigenvalues of A) decides. The decision is
// h rho(A) <= limit whatever D is: D only spares the eigenvalues.
#pragma once

#include <Eigen/Core>

namespace coaxid {

// The largest absolute row sum of D A D^-1, D = diag(scales) (scales empty:
// D = I): an upper bound on A's spectral radius.
double ScaledGershgorinBound(const Eigen::MatrixXd& A, const Eigen::VectorXd& scales);

// Osborne's balancing of a square A: positive scales d with the off-diagonal
// row and column sums of D A D^-1 about equal, state by state (a few sweeps).
Eigen::VectorXd BalancingScales(const Eigen::MatrixXd& A);

// A's spectral radius from its eigenvalues; +infinity if they cannot be
// computed (a non-finite A).
double SpectralRadius(const Eigen::MatrixXd& A);

class Rk4StabilityTest {
 public:
  explicit Rk4StabilityTest(double limit) : limit_(limit) {}
  // h rho(A) <= limit.
  bool Stable(double h, const Eigen::MatrixXd& A);
  // Forgets the balancing (the decisions do not depend on it).
  void Reset() { scales_.resize(0); }
  // How often each test decided, since construction.
  long by_row_sums() const { return by_row_sums_; }
  long by_eigenvalues() const { return by_eigenvalues_; }

 private:
  double limit_;
  Eigen::VectorXd scales_;  // D's diagonal; empty: not made yet
  long by_row_sums_ = 0, by_eigenvalues_ = 0;
};

}  // namespace coaxid
