#include "ident/linearised_fit.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <thread>

#include <Eigen/Eigenvalues>
#include <glog/logging.h>

#include "ident/free_parameters.h"
#include "ident/output_error_costs.h"
#include "ident/residual_analysis.h"

namespace coaxid {
namespace {

// One cluster's residual block: its cost, where its parameter blocks sit
// among the columns, and the values to evaluate it at.
struct ClusterJob {
  std::unique_ptr<ceres::CostFunction> cost;
  std::vector<const double*> blocks;
  std::vector<int> block_columns;  // first column of each parameter block
  // Filled by Evaluate:
  bool ok = false;
  std::vector<int> columns;        // global column of each local column
  Eigen::MatrixXd normal;          // local J^T J
  Eigen::VectorXd gradient;        // local J^T r
  double rss = 0;
};

void Evaluate(ClusterJob* job) {
  const ceres::CostFunction& cost = *job->cost;
  const int R = cost.num_residuals();
  const std::vector<int32_t>& sizes = cost.parameter_block_sizes();
  int width = 0;
  for (int s : sizes) width += s;
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  std::vector<RowMajor> blocks;
  std::vector<double*> jacobians;
  for (int s : sizes) {
    blocks.emplace_back(R, s);
    jacobians.push_back(blocks.back().data());
  }
  Eigen::VectorXd r(R);
  if (!cost.Evaluate(job->blocks.data(), r.data(), jacobians.data()) || !r.allFinite()) return;
  Eigen::MatrixXd J(R, width);
  int offset = 0;
  for (size_t b = 0; b < sizes.size(); ++b) {
    J.middleCols(offset, sizes[b]) = blocks[b];
    for (int k = 0; k < sizes[b]; ++k) job->columns.push_back(job->block_columns[b] + k);
    offset += sizes[b];
  }
  if (!J.allFinite()) return;
  job->normal = J.transpose() * J;
  job->gradient = J.transpose() * r;
  job->rss = r.squaredNorm();
  job->ok = true;
}

}  // namespace

int LinearisedFit::ParameterColumn(const std::string& name) const {
  for (size_t k = 0; k < parameter_names.size(); ++k) {
    if (parameter_names[k] == name) return num_state_columns + static_cast<int>(k);
  }
  return -1;
}

bool LineariseFit(const Vehicle& vehicle, const std::vector<EstimationLog>& logs,
                  const std::vector<FittedSegments>& segments, const NoiseWeights& noise,
                  const OutputErrorOptions& options, LinearisedFit* out, std::string* why) {
  CHECK_EQ(logs.size(), segments.size());
  const FreeParameters free(vehicle.parameters);
  const Eigen::VectorXd theta_scaled = free.ScaledValues();
  int state_columns = 0;
  for (const FittedSegments& s : segments) state_columns += kNumStates * s.starts.size();
  const int theta_column = state_columns;

  std::vector<ClusterJob> jobs;
  int segment_column = 0;
  for (size_t i = 0; i < logs.size(); ++i) {
    const EstimationLog& log = logs[i];
    std::vector<double> channel_std;
    for (const std::string& name : log.channel_names) channel_std.push_back(noise.For(name));
    if (log.kind == LogKind::kBalance) {
      for (int first = 0; first < log.NumRows();) {
        int end = first + 1;
        while (end < log.NumRows() && log.inputs.input(end) == log.inputs.input(first)) ++end;
        ClusterJob job;
        job.cost = std::make_unique<BalanceRowsCost>(vehicle.model, free, log, first, end,
                                                     channel_std);
        job.blocks = {theta_scaled.data()};
        job.block_columns = {theta_column};
        if (job.cost->num_residuals() > 0) jobs.push_back(std::move(job));
        first = end;
      }
      continue;
    }
    const FittedSegments& seg = segments[i];
    CHECK(!seg.starts.empty()) << log.source << ": a flight log needs its fitted segments";
    for (size_t j = 0; j < seg.starts.size(); ++j) {
      const bool has_next = j + 1 < seg.starts.size();
      const int last = has_next ? seg.starts[j + 1] : log.NumRows() - 1;
      ClusterJob job;
      job.cost = std::make_unique<FlightSegmentCost>(vehicle.model, free, log, seg.starts[j], last,
                                                     has_next, channel_std,
                                                     options.continuity_std, options.integrator);
      job.blocks = {seg.states[j].data(), theta_scaled.data()};
      job.block_columns = {segment_column + kNumStates * static_cast<int>(j), theta_column};
      if (has_next) {
        job.blocks.push_back(seg.states[j + 1].data());
        job.block_columns.push_back(segment_column + kNumStates * static_cast<int>(j + 1));
      }
      jobs.push_back(std::move(job));
    }
    segment_column += kNumStates * static_cast<int>(seg.starts.size());
  }

  // Clusters are independent simulations: evaluated on the fit's threads.
  const int threads = std::max(1, std::min<int>(options.num_threads, jobs.size()));
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) {
    pool.emplace_back([&jobs, t, threads] {
      for (size_t k = t; k < jobs.size(); k += threads) Evaluate(&jobs[k]);
    });
  }
  for (std::thread& t : pool) t.join();

  const int D = state_columns + free.size();
  LinearisedFit& f = *out;
  f = LinearisedFit();
  f.num_state_columns = state_columns;
  f.parameter_names = free.names();
  f.parameter_scales = free.scales();
  f.normal = Eigen::MatrixXd::Zero(D, D);
  f.gradient = Eigen::VectorXd::Zero(D);
  for (ClusterJob& job : jobs) {
    if (!job.ok) {
      *why = "the model cannot be evaluated along the fitted trajectory (CVODE failed)";
      return false;
    }
    Eigen::VectorXd b = Eigen::VectorXd::Zero(D);
    for (size_t a = 0; a < job.columns.size(); ++a) {
      b[job.columns[a]] += job.gradient[a];
      for (size_t c = 0; c < job.columns.size(); ++c) {
        f.normal(job.columns[a], job.columns[c]) += job.normal(a, c);
      }
    }
    f.gradient += b;
    f.cluster_gradients.push_back(std::move(b));
    f.cluster_residuals.push_back(job.cost->num_residuals());
    f.rss += job.rss;
    f.num_residuals += job.cost->num_residuals();
  }
  return true;
}

ColumnTester::ColumnTester(const LinearisedFit& fit, const std::vector<int>& nuisance)
    : fit_(fit), nuisance_(nuisance) {
  const int n = static_cast<int>(nuisance.size());
  Eigen::MatrixXd A(n, n);
  for (int a = 0; a < n; ++a) {
    for (int c = 0; c < n; ++c) A(a, c) = fit.normal(nuisance[a], nuisance[c]);
  }
  // Jacobi scaling makes the rank threshold relative to each column's own size.
  inverse_scale_.resize(n);
  for (int a = 0; a < n; ++a) {
    inverse_scale_[a] = A(a, a) > 0 ? 1 / std::sqrt(A(a, a)) : 0.0;
  }
  const Eigen::MatrixXd scaled = inverse_scale_.asDiagonal() * A * inverse_scale_.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(scaled);
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  const double floor = 1e-10 * std::max(1.0, lambda.size() ? lambda.maxCoeff() : 1.0);
  std::vector<int> kept;
  for (int k = 0; k < lambda.size(); ++k) {
    if (lambda[k] > floor) kept.push_back(k);
  }
  rank_ = static_cast<int>(kept.size());
  basis_.resize(n, rank_);
  inverse_eigenvalues_.resize(rank_);
  for (int k = 0; k < rank_; ++k) {
    basis_.col(k) = eig.eigenvectors().col(kept[k]);
    inverse_eigenvalues_[k] = 1 / lambda[kept[k]];
  }
}

ColumnTest ColumnTester::Test(const std::vector<int>& tested, const Eigen::VectorXd* values) const {
  ColumnTest t;
  const int q = static_cast<int>(tested.size());
  const int n = static_cast<int>(nuisance_.size());
  const int M = static_cast<int>(fit_.cluster_gradients.size());
  t.q = q;
  t.clusters = M;
  if (q == 0) {
    t.why_not = "no column to test";
    return t;
  }
  // X = N_00^+ N_0Z (n x q), S = N_ZZ - N_Z0 X.
  Eigen::MatrixXd N0Z(n, q), NZZ(q, q);
  for (int a = 0; a < n; ++a) {
    for (int c = 0; c < q; ++c) N0Z(a, c) = fit_.normal(nuisance_[a], tested[c]);
  }
  for (int a = 0; a < q; ++a) {
    for (int c = 0; c < q; ++c) NZZ(a, c) = fit_.normal(tested[a], tested[c]);
  }
  const Eigen::MatrixXd X =
      inverse_scale_.asDiagonal() *
      (basis_ * (inverse_eigenvalues_.asDiagonal() *
                 (basis_.transpose() * (inverse_scale_.asDiagonal() * N0Z))));
  Eigen::MatrixXd S = NZZ - N0Z.transpose() * X;
  S = 0.5 * (S + S.transpose());
  // The tested columns must keep a part of their own after the projection:
  // below 1e-8 of their size they are a combination of the nuisance columns.
  for (int c = 0; c < q; ++c) {
    if (!(S(c, c) > 1e-8 * NZZ(c, c)) || !(NZZ(c, c) > 0)) {
      t.why_not =
          "its regressors are explained by the parameters already estimated (not separable in "
          "these logs)";
      return t;
    }
  }
  if (M < q + 2) {
    t.why_not = "too few independent clusters (" + std::to_string(M) +
                ") for a covariance of its score";
    return t;
  }
  // Projected cluster scores g_c = b_c[Z] - X^T b_c[0] (q x M).
  Eigen::MatrixXd g(q, M);
  for (int m = 0; m < M; ++m) {
    const Eigen::VectorXd& b = fit_.cluster_gradients[m];
    Eigen::VectorXd b0(n);
    for (int a = 0; a < n; ++a) b0[a] = b[nuisance_[a]];
    for (int c = 0; c < q; ++c) g(c, m) = b[tested[c]];
    g.col(m) -= X.transpose() * b0;
  }
  // Sign convention: r = model - measured, so the step that lowers r^T r is -S^-1 G.
  const Eigen::VectorXd G = g.rowwise().sum();
  const Eigen::LDLT<Eigen::MatrixXd> S_ldlt(S);
  t.step = -S_ldlt.solve(G);
  t.predicted_rss_drop = G.dot(S_ldlt.solve(G));
  const Eigen::VectorXd mean = G / M;
  const Eigen::MatrixXd centred = g.colwise() - mean;
  const Eigen::MatrixXd C = centred * centred.transpose() / (M - 1);
  const Eigen::LDLT<Eigen::MatrixXd> C_ldlt(C);
  double T2;
  if (values == nullptr) {
    T2 = M * mean.dot(C_ldlt.solve(mean));
  } else {
    // Cov(delta) = S^-1 (M C) S^-1, so T^2 = delta^T S (M C)^-1 S delta.
    const Eigen::VectorXd s_delta = S * *values;
    T2 = s_delta.dot(C_ldlt.solve(s_delta)) / M;
  }
  if (!std::isfinite(T2) || C_ldlt.info() != Eigen::Success) {
    t.why_not = "the covariance of its score is singular";
    return t;
  }
  t.ok = true;
  t.statistic = std::max(0.0, T2 * (M - q) / (q * (M - 1.0)));
  t.p_value = FSurvival(t.statistic, q, M - q);
  const int dof = std::max(1, fit_.num_residuals - static_cast<int>(nuisance_.size()) - q);
  const double sigma2 = fit_.rss / dof;
  t.white_statistic = values == nullptr ? t.predicted_rss_drop / q / sigma2
                                        : values->dot(S * *values) / q / sigma2;
  t.white_p_value = FSurvival(t.white_statistic, q, dof);
  return t;
}

std::vector<int> ColumnsExcept(const LinearisedFit& fit, const std::vector<std::string>& parameters) {
  std::vector<int> out;
  for (int c = 0; c < fit.num_state_columns; ++c) out.push_back(c);
  for (size_t k = 0; k < fit.parameter_names.size(); ++k) {
    if (std::find(parameters.begin(), parameters.end(), fit.parameter_names[k]) == parameters.end()) {
      out.push_back(fit.num_state_columns + static_cast<int>(k));
    }
  }
  return out;
}

std::vector<int> ParameterColumns(const LinearisedFit& fit, const std::vector<std::string>& parameters) {
  std::vector<int> out;
  for (const std::string& name : parameters) {
    const int c = fit.ParameterColumn(name);
    CHECK_GE(c, 0) << name << " is not free in the linearised fit";
    out.push_back(c);
  }
  return out;
}

}  // namespace coaxid
