#include "ident/output_error/information.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "core/errors.h"

namespace coaxid {
namespace {

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The segment start block's size: the model's states, effect states included.
int SegmentStates(const LogResidualBlocks& log) {
  return log.segments.empty() ? 0 : log.segments.front()->parameter_block_sizes()[0];
}

// Columns of the free segment-state coordinates in H_ss: index[j][s], -1 for
// a coordinate held constant.
std::vector<std::vector<int>> StateColumns(const LogResidualBlocks& log, int* next) {
  const int ns = SegmentStates(log);
  std::vector<std::vector<int>> index(log.segments.size(), std::vector<int>(ns));
  for (size_t j = 0; j < log.segments.size(); ++j) {
    for (int s = 0; s < ns; ++s) {
      const bool held = j == 0 && std::find(log.held_states.begin(), log.held_states.end(), s) !=
                                      log.held_states.end();
      index[j][s] = held ? -1 : (*next)++;
    }
  }
  return index;
}

}  // namespace

OutputErrorInformation ComputeOutputErrorInformation(const std::vector<LogResidualBlocks>& logs,
                                                     const double* theta_scaled, int P,
                                                     bool keep_flight_rows) {
  OutputErrorInformation out;
  Eigen::MatrixXd H_tt = Eigen::MatrixXd::Zero(P, P);
  Eigen::MatrixXd balance = Eigen::MatrixXd::Zero(P, P);
  int n = 0;
  std::vector<std::vector<std::vector<int>>> columns;
  for (const LogResidualBlocks& log : logs) columns.push_back(StateColumns(log, &n));
  Eigen::MatrixXd H_st = Eigen::MatrixXd::Zero(n, P);
  std::vector<Eigen::Triplet<double>> H_ss;
  // d r / d s of the output rows, kept to marginalise the rows' sensitivities.
  std::vector<Eigen::MatrixXd> output_state_jacobians(logs.size());
  std::vector<std::vector<int>> output_segment(logs.size());
  out.flight.resize(logs.size());

  for (size_t i = 0; i < logs.size(); ++i) {
    const LogResidualBlocks& log = logs[i];
    for (const BalanceRowsCost* cost : log.balance) {
      RowMajor J(cost->num_residuals(), P);
      Eigen::VectorXd r(cost->num_residuals());
      double* jacobians[] = {J.data()};
      if (!cost->Evaluate(&theta_scaled, r.data(), jacobians)) {
        throw ComputationError(log.log->source + ": the balance model cannot be evaluated at the "
                               "solution");
      }
      H_tt.noalias() += J.transpose() * J;
      balance.noalias() += J.transpose() * J;
    }
    if (log.segments.empty()) continue;
    OutputErrorInformation::FlightRows& rows = out.flight[i];
    const int channels = log.log->NumChannels(), N = log.log->NumRows();
    const int ns = SegmentStates(log);
    if (keep_flight_rows) {
      rows.num_channels = channels;
      rows.sensitivities = Eigen::MatrixXd::Zero(N * channels, P);
      rows.residuals = Eigen::MatrixXd::Zero(N, channels);
      rows.present = Eigen::MatrixXd::Zero(N, channels);
      output_state_jacobians[i] = Eigen::MatrixXd::Zero(N * channels, ns);
      output_segment[i].assign(N * channels, -1);
    }
    for (size_t j = 0; j < log.segments.size(); ++j) {
      const FlightSegmentCost& segment = *log.segments[j];
      const ceres::CostFunction& cost =
          keep_flight_rows || log.compressed.empty() ? segment : *log.compressed[j];
      const int m = cost.num_residuals();
      const bool next = segment.has_next();
      RowMajor J_s(m, ns), J_t(m, P), J_n(next ? m : 0, ns);
      Eigen::VectorXd r(m);
      const double* parameters[] = {log.segment_states[j], theta_scaled,
                                    next ? log.segment_states[j + 1] : nullptr};
      double* jacobians[] = {J_s.data(), J_t.data(), next ? J_n.data() : nullptr};
      if (!cost.Evaluate(parameters, r.data(), jacobians)) {
        throw ComputationError(log.log->source + ": the model cannot be simulated at the solution "
                               "(rows " + std::to_string(segment.first()) + "-" +
                               std::to_string(segment.last()) + ")");
      }
      for (int s = 0; s < ns; ++s) {
        if (columns[i][j][s] < 0) J_s.col(s).setZero();
      }
      // [J_s | J_n] against its state columns.
      RowMajor A(m, next ? 2 * ns : ns);
      A.leftCols(ns) = J_s;
      if (next) A.rightCols(ns) = J_n;
      std::vector<int> index(columns[i][j].begin(), columns[i][j].end());
      if (next) index.insert(index.end(), columns[i][j + 1].begin(), columns[i][j + 1].end());
      const Eigen::MatrixXd AtA = A.transpose() * A, AtJ = A.transpose() * J_t;
      for (int a = 0; a < A.cols(); ++a) {
        if (index[a] < 0) continue;
        H_st.row(index[a]) += AtJ.row(a);
        for (int b = 0; b < A.cols(); ++b) {
          if (index[b] >= 0 && AtA(a, b) != 0) H_ss.emplace_back(index[a], index[b], AtA(a, b));
        }
      }
      H_tt.noalias() += J_t.transpose() * J_t;
      if (!keep_flight_rows) continue;
      const auto& terms = segment.terms();
      for (size_t t = 0; t < terms.size(); ++t) {
        const int row = terms[t].row * channels + terms[t].column;
        rows.sensitivities.row(row) = J_t.row(t);
        output_state_jacobians[i].row(row) = J_s.row(t);
        output_segment[i][row] = static_cast<int>(j);
        rows.residuals(terms[t].row, terms[t].column) = r[t];
        rows.present(terms[t].row, terms[t].column) = 1;
      }
    }
  }
  out.information = H_tt;
  out.balance_information = balance;
  if (n == 0) return out;
  Eigen::SparseMatrix<double> H(n, n);
  H.setFromTriplets(H_ss.begin(), H_ss.end());  // duplicates are summed
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(H);
  if (ldlt.info() != Eigen::Success) return out;  // cannot marginalise: conditional information
  const Eigen::MatrixXd X = ldlt.solve(H_st);     // H_ss^-1 H_st
  out.information = H_tt - H_st.transpose() * X;
  if (!keep_flight_rows) return out;
  // G = J_t - J_s X for every output row, X restricted to its segment's states.
  for (size_t i = 0; i < logs.size(); ++i) {
    for (size_t row = 0; row < output_segment[i].size(); ++row) {
      const int j = output_segment[i][row];
      if (j < 0) continue;
      for (int s = 0; s < static_cast<int>(columns[i][j].size()); ++s) {
        const int c = columns[i][j][s];
        if (c >= 0) {
          out.flight[i].sensitivities.row(row) -= output_state_jacobians[i](row, s) * X.row(c);
        }
      }
    }
  }
  return out;
}

namespace {

// Cross-correlation of the weighted residual vectors at lag tau:
// R(a, b) = mean over k of w_a(k) w_b(k + tau), over the pairs where both exist.
Eigen::MatrixXd ResidualCorrelation(const OutputErrorInformation::FlightRows& rows, int tau) {
  const int N = static_cast<int>(rows.residuals.rows());
  const Eigen::MatrixXd sums =
      rows.residuals.topRows(N - tau).transpose() * rows.residuals.bottomRows(N - tau);
  const Eigen::MatrixXd counts =
      rows.present.topRows(N - tau).transpose() * rows.present.bottomRows(N - tau);
  return (counts.array() > 0).select(sums.array() / counts.array().max(1.0), 0.0).matrix();
}

// The last lag before the autocorrelation of every channel has entered the
// +-2/sqrt(N) band of white noise (0 for white residuals), capped at max_lag.
int TruncationLag(const OutputErrorInformation::FlightRows& rows, int max_lag) {
  const int N = static_cast<int>(rows.residuals.rows());
  const Eigen::VectorXd r0 = ResidualCorrelation(rows, 0).diagonal();
  int lag = 0;
  for (int c = 0; c < rows.num_channels; ++c) {
    const double n = rows.present.col(c).sum();
    if (n < 2 || !(r0[c] > 0)) continue;
    const double band = 2.0 / std::sqrt(n);
    int tau = 1;
    for (; tau <= std::min(max_lag, N - 1); ++tau) {
      const Eigen::VectorXd a = rows.residuals.col(c).head(N - tau);
      const Eigen::VectorXd b = rows.residuals.col(c).tail(N - tau);
      const double pairs = rows.present.col(c).head(N - tau).dot(rows.present.col(c).tail(N - tau));
      if (pairs < 1 || std::fabs(a.dot(b) / pairs / r0[c]) < band) break;
    }
    lag = std::max(lag, std::min(tau - 1, max_lag));
  }
  return lag;
}

}  // namespace

ColouredResidualCorrection CorrectForColouredResiduals(const OutputErrorInformation& info,
                                                       const Eigen::MatrixXd& covariance_scaled,
                                                       int max_lag) {
  const int P = static_cast<int>(info.information.rows());
  // sum_k sum_j G_k^T Rvv(k - j) G_j replaces the white part sum_k G_k^T G_k
  // of the information; the other rows (balance, continuity) stay as they are.
  Eigen::MatrixXd middle = info.information;
  ColouredResidualCorrection out;
  for (const OutputErrorInformation::FlightRows& rows : info.flight) {
    if (rows.num_channels == 0) continue;
    const int C = rows.num_channels, N = static_cast<int>(rows.residuals.rows());
    const Eigen::MatrixXd& G = rows.sensitivities;  // (N C) x P, row k C + c
    middle.noalias() -= G.transpose() * G;
    const int L = TruncationLag(rows, max_lag);
    out.lags.push_back(L);
    Eigen::MatrixXd RG(N * C, P);
    for (int tau = 0; tau <= L; ++tau) {
      // Column-major (N C) x P viewed as C x (N P): column k + N p holds
      // G_k(:, p), so one product applies Rvv(tau) to every sample's block.
      Eigen::Map<const Eigen::MatrixXd> blocks(G.data(), C, static_cast<Eigen::Index>(N) * P);
      Eigen::Map<Eigen::MatrixXd>(RG.data(), C, static_cast<Eigen::Index>(N) * P).noalias() =
          ResidualCorrelation(rows, tau) * blocks;
      // T(tau) = sum_k G_k^T Rvv(tau) G_{k+tau}; lag -tau contributes T^T.
      const Eigen::MatrixXd T =
          G.topRows(C * (N - tau)).transpose() * RG.bottomRows(C * (N - tau));
      middle += tau == 0 ? T : Eigen::MatrixXd(T + T.transpose());
    }
  }
  out.covariance_scaled = covariance_scaled * middle * covariance_scaled;
  out.covariance_scaled = 0.5 * (out.covariance_scaled + out.covariance_scaled.transpose());
  return out;
}

void RescaleParameters(const Eigen::VectorXd& factors, OutputErrorInformation* info) {
  const Eigen::VectorXd inverse = factors.cwiseInverse();
  info->information = inverse.asDiagonal() * info->information * inverse.asDiagonal();
  info->balance_information =
      inverse.asDiagonal() * info->balance_information * inverse.asDiagonal();
  for (OutputErrorInformation::FlightRows& rows : info->flight) {
    if (rows.sensitivities.cols() == inverse.size()) {
      rows.sensitivities = rows.sensitivities * inverse.asDiagonal();
    }
  }
}

void DropParameter(int k, OutputErrorInformation* info) {
  auto drop_column = [k](Eigen::MatrixXd* m) {
    const Eigen::Index n = m->cols() - 1;
    m->middleCols(k, n - k) = m->rightCols(n - k).eval();
    m->conservativeResize(Eigen::NoChange, n);
  };
  for (Eigen::MatrixXd* M : {&info->information, &info->balance_information}) {
    drop_column(M);
    M->transposeInPlace();
    drop_column(M);
  }
  for (OutputErrorInformation::FlightRows& rows : info->flight) {
    if (rows.sensitivities.cols() > k) drop_column(&rows.sensitivities);
  }
}

}  // namespace coaxid
