// A multiple-shooting segment as Ceres sees it: its output residuals
// compressed to the normal equations they give, so the solver stores a few
// dozen rows a segment instead of one per logged value (a 1 s segment at
// 200 Hz: 3000 rows x 24 columns, 0.6 MB; an hour of flight: 2 GB).
//
// With r the segment's weighted output residuals (FlightSegmentCost) and
// J = [dr/ds_j | dr/dtheta] (n = 12 + P columns), the thin QR J = Q1 R gives
// the residual vector
//   r_c = [ Q1^T r ; sqrt(|r|^2 - |Q1^T r|^2) ]          (n + 1 rows)
// with Jacobian [ R ; 0 ]: |r_c| = |r|, J_c^T J_c = J^T J and J_c^T r_c = J^T r,
// so the cost, the gradient, the Gauss-Newton and Levenberg-Marquardt steps,
// the Jacobi scaling and a robust loss on the block are those of the full
// block (the same iterates up to rounding). The continuity residuals
// follow unchanged. R is the Cholesky factor of J^T J and Q1^T r is
// R^-T J^T r (CompressRows): one cache-blocked pass over J, a third of a
// Householder QR's time at 3000 x 24 (Ceres forms the normal equations of R
// in any case). Where only the cost is asked (a trial point), the
// output part is [0 ; |r|]: same norm. A segment with fewer output rows
// than n + 1 is passed through uncompressed.
//
// The compressed block at the last point it was evaluated with Jacobians is
// kept (n + 1 rows, not the segment's sensitivities) and served again at
// that point (a noise relaxation re-solves from the previous solution);
// new channel weights (SetChannelStd here, never on the segment itself)
// drop it. So is the last evaluation without Jacobians (a trial point).
#pragma once

#include <memory>
#include <vector>

#include <ceres/ceres.h>
#include <Eigen/Core>

#include "ident/output_error/costs.h"

namespace coaxid {

// Output rows compressed (m x n Jacobian A, residuals r, m > n): R (n x n,
// upper triangular) with R^T R = A^T A, head = R^-T A^T r (Q1^T r) and
// rest = |Q2^T r|, so |head|^2 + rest^2 = |r|^2. By Cholesky of A^T A, a
// column dependent on the ones before it (sin^2 of its angle to their span
// below kDependentColumn: a parameter its segment does not see) given a zero
// row, where |r|^2 - |head|^2 keeps at least 8 of its 16 digits
// (kMinUnexplainedShare); else by Householder QR.
struct CompressedRows {
  Eigen::VectorXd head;
  double rest = 0;
  Eigen::MatrixXd R;
  bool by_cholesky = false;
};
inline constexpr double kDependentColumn = 1e-12;  // well above the pivots' round-off, n eps
inline constexpr double kMinUnexplainedShare = 1e-8;  // of |r|^2
CompressedRows CompressRows(const Eigen::MatrixXd& A, const Eigen::VectorXd& r);

class CompressedSegmentCost : public ceres::CostFunction {
 public:
  // Takes ownership of the segment.
  explicit CompressedSegmentCost(std::unique_ptr<FlightSegmentCost> segment);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  // Evaluates the block at `parameters` (with its Jacobian if `jacobians`)
  // and keeps the result, so that Evaluate there only copies it out: how
  // ParallelSegmentEvaluation runs the segments side by side before Ceres
  // asks for them one after the other.
  void Prepare(double const* const* parameters, bool jacobians) const;

  FlightSegmentCost* segment() const { return segment_.get(); }
  bool compressed() const { return compressed_; }

  // New noise std per log channel: the segment's, and the kept block is dropped.
  void SetChannelStd(const std::vector<double>& channel_std);

 private:
  std::unique_ptr<FlightSegmentCost> segment_;
  bool compressed_;
  int states_;  // the segment start block: the model's states (effect states after the 12)
  int n_;       // states_ + P compressed columns
  // The kept compressed block: residuals (n + 1 + continuity) and the
  // Jacobian over [s_j | theta] (R, n x n upper triangular).
  struct Kept {
    bool valid = false;
    Eigen::VectorXd start_state, theta_scaled, next_state;
    Eigen::VectorXd residuals;
    Eigen::MatrixXd R;
    // The continuity rows' Jacobians (12 x 12, 12 x P, 12 x 12).
    Eigen::MatrixXd continuity_state, continuity_theta, continuity_next;
  };
  mutable Kept kept_;
  // The last evaluation without Jacobians (a trial point): its point and
  // residuals (n + 1 + continuity rows), served again there.
  struct KeptResiduals {
    bool valid = false, ok = false;
    Eigen::VectorXd start_state, theta_scaled, next_state;
    Eigen::VectorXd residuals;
  };
  mutable KeptResiduals trial_;
  // True if the point `parameters` is (start_state, theta_scaled, next_state).
  bool At(double const* const* parameters, const Eigen::VectorXd& start_state,
          const Eigen::VectorXd& theta_scaled, const Eigen::VectorXd& next_state) const;
  // The compressed block and its Jacobian at `parameters`, into kept_.
  bool EvaluateKept(double const* const* parameters) const;
  // The compressed residuals at `parameters` without Jacobians, into trial_.
  bool EvaluateTrial(double const* const* parameters) const;
};

}  // namespace coaxid
