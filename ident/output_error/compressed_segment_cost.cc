#include "ident/output_error/compressed_segment_cost.h"

#include <cmath>

#include <Eigen/QR>

namespace coaxid {

namespace {
using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
}  // namespace

CompressedRows CompressRows(const Eigen::MatrixXd& A, const Eigen::VectorXd& r) {
  const int n = static_cast<int>(A.cols());
  CompressedRows c;
  thread_local Eigen::MatrixXd N;
  N.setZero(n, n);
  N.selfadjointView<Eigen::Upper>().rankUpdate(A.transpose());  // A^T A, one blocked pass
  const Eigen::VectorXd g = A.transpose() * r;
  // N = R^T R, row by row; a column within kDependentColumn of the span of
  // the ones before it (a parameter the segment does not see: a zero column)
  // gets a zero row, and head = R^-T g nothing along it.
  c.R.setZero(n, n);
  c.head.setZero(n);
  for (int i = 0; i < n; ++i) {
    const double d = N(i, i) - c.R.col(i).head(i).squaredNorm();
    if (!(d > kDependentColumn * N(i, i))) continue;
    const double rii = std::sqrt(d);
    c.R(i, i) = rii;
    for (int j = i + 1; j < n; ++j) {
      c.R(i, j) = (N(i, j) - c.R.col(i).head(i).dot(c.R.col(j).head(i))) / rii;
    }
    c.head[i] = (g[i] - c.R.col(i).head(i).dot(c.head.head(i))) / rii;
  }
  const double r2 = r.squaredNorm(), rest2 = r2 - c.head.squaredNorm();
  if (c.R.allFinite() && c.head.allFinite() && rest2 >= kMinUnexplainedShare * r2) {
    c.rest = std::sqrt(rest2);
    c.by_cholesky = true;
    return c;
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
  const Eigen::VectorXd qtr = qr.householderQ().adjoint() * r;
  c.head = qtr.head(n);
  c.rest = qtr.tail(A.rows() - n).norm();  // |Q2^T r|
  c.R = qr.matrixQR().topRows(n).triangularView<Eigen::Upper>();
  return c;
}

CompressedSegmentCost::CompressedSegmentCost(std::unique_ptr<FlightSegmentCost> segment)
    : segment_(std::move(segment)) {
  const int P = segment_->parameter_block_sizes()[1];
  states_ = segment_->parameter_block_sizes()[0];  // the model's, effect states included
  n_ = states_ + P;
  compressed_ = segment_->NumOutputResiduals() > n_ + 1;
  *mutable_parameter_block_sizes() = segment_->parameter_block_sizes();
  const int continuity = segment_->num_residuals() - segment_->NumOutputResiduals();
  set_num_residuals(compressed_ ? n_ + 1 + continuity : segment_->num_residuals());
}

void CompressedSegmentCost::SetChannelStd(const std::vector<double>& channel_std) {
  segment_->SetChannelStd(channel_std);
  kept_.valid = false;
  trial_.valid = false;
}

bool CompressedSegmentCost::At(double const* const* parameters, const Eigen::VectorXd& start_state,
                               const Eigen::VectorXd& theta_scaled,
                               const Eigen::VectorXd& next_state) const {
  const int P = n_ - states_;
  return Eigen::Map<const Eigen::VectorXd>(parameters[0], states_) == start_state &&
         Eigen::Map<const Eigen::VectorXd>(parameters[1], P) == theta_scaled &&
         (!segment_->has_next() ||
          Eigen::Map<const Eigen::VectorXd>(parameters[2], states_) == next_state);
}

bool CompressedSegmentCost::EvaluateTrial(double const* const* parameters) const {
  const int P = n_ - states_;
  const int m = segment_->num_residuals(), m_out = segment_->NumOutputResiduals();
  const int continuity = m - m_out;
  thread_local Eigen::VectorXd r;
  r.resize(m);
  trial_.ok = segment_->Evaluate(parameters, r.data(), nullptr);
  if (trial_.ok) {
    trial_.residuals.resize(num_residuals());
    trial_.residuals.head(n_).setZero();
    trial_.residuals[n_] = r.head(m_out).norm();
    trial_.residuals.tail(continuity) = r.tail(continuity);
  }
  trial_.start_state = Eigen::Map<const Eigen::VectorXd>(parameters[0], states_);
  trial_.theta_scaled = Eigen::Map<const Eigen::VectorXd>(parameters[1], P);
  if (segment_->has_next()) {
    trial_.next_state = Eigen::Map<const Eigen::VectorXd>(parameters[2], states_);
  }
  trial_.valid = true;
  return trial_.ok;
}

bool CompressedSegmentCost::EvaluateKept(double const* const* parameters) const {
  const bool has_next = segment_->has_next();
  const int P = n_ - states_;
  const int m = segment_->num_residuals(), m_out = segment_->NumOutputResiduals();
  const int continuity = m - m_out;
  thread_local RowMajor J_state, J_theta, J_next;
  thread_local Eigen::VectorXd r;
  J_state.resize(m, states_);
  J_theta.resize(m, P);
  J_next.resize(has_next ? m : 0, states_);
  r.resize(m);
  double* full[] = {J_state.data(), J_theta.data(), has_next ? J_next.data() : nullptr};
  if (!segment_->Evaluate(parameters, r.data(), full)) return false;
  thread_local Eigen::MatrixXd A;
  A.resize(m_out, n_);
  A.leftCols(states_) = J_state.topRows(m_out);
  A.rightCols(P) = J_theta.topRows(m_out);
  CompressedRows rows = CompressRows(A, r.head(m_out));
  kept_.residuals.resize(num_residuals());
  kept_.residuals.head(n_) = rows.head;
  kept_.residuals[n_] = rows.rest;
  kept_.residuals.tail(continuity) = r.tail(continuity);
  kept_.R = std::move(rows.R);
  kept_.continuity_state = J_state.bottomRows(continuity);
  kept_.continuity_theta = J_theta.bottomRows(continuity);
  kept_.continuity_next =
      has_next ? Eigen::MatrixXd(J_next.bottomRows(continuity)) : Eigen::MatrixXd();
  kept_.start_state = Eigen::Map<const Eigen::VectorXd>(parameters[0], states_);
  kept_.theta_scaled = Eigen::Map<const Eigen::VectorXd>(parameters[1], P);
  if (has_next) kept_.next_state = Eigen::Map<const Eigen::VectorXd>(parameters[2], states_);
  kept_.valid = true;
  return true;
}

void CompressedSegmentCost::Prepare(double const* const* parameters, bool jacobians) const {
  if (!compressed_) {
    // Served by the segment's own cache of its last simulation (not its
    // sensitivities: those are asked for again).
    if (!jacobians) {
      thread_local Eigen::VectorXd r;
      r.resize(segment_->num_residuals());
      segment_->Evaluate(parameters, r.data(), nullptr);
    }
    return;
  }
  if (kept_.valid && At(parameters, kept_.start_state, kept_.theta_scaled, kept_.next_state)) return;
  if (jacobians) {
    EvaluateKept(parameters);
  } else if (!(trial_.valid &&
               At(parameters, trial_.start_state, trial_.theta_scaled, trial_.next_state))) {
    EvaluateTrial(parameters);
  }
}

bool CompressedSegmentCost::Evaluate(double const* const* parameters, double* residuals,
                                     double** jacobians) const {
  if (!compressed_) return segment_->Evaluate(parameters, residuals, jacobians);
  const bool has_next = segment_->has_next();
  const int P = n_ - states_;
  const int continuity = segment_->num_residuals() - segment_->NumOutputResiduals();
  const bool want = jacobians && (jacobians[0] || jacobians[1] || (has_next && jacobians[2]));
  Prepare(parameters, want);  // a no-op where the callback already prepared this point
  if (!(kept_.valid && At(parameters, kept_.start_state, kept_.theta_scaled, kept_.next_state))) {
    // Not at the kept block: the Jacobian's evaluation failed, or a trial point.
    if (want || !trial_.ok) return false;
    Eigen::Map<Eigen::VectorXd>(residuals, num_residuals()) = trial_.residuals;
    return true;
  }
  Eigen::Map<Eigen::VectorXd>(residuals, num_residuals()) = kept_.residuals;
  if (!jacobians) return true;
  const int rows = num_residuals();
  auto fill = [&](int block, int columns, const Eigen::MatrixXd& top,
                  const Eigen::MatrixXd& bottom) {
    if (!jacobians[block]) return;
    Eigen::Map<RowMajor> J(jacobians[block], rows, columns);
    J.setZero();
    if (top.size() > 0) J.topRows(n_) = top;
    J.bottomRows(continuity) = bottom;
  };
  fill(0, states_, kept_.R.leftCols(states_), kept_.continuity_state);
  fill(1, P, kept_.R.rightCols(P), kept_.continuity_theta);
  if (has_next) fill(2, states_, Eigen::MatrixXd(), kept_.continuity_next);
  return true;
}

}  // namespace coaxid
