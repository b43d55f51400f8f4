#include "ident/discover/linearised_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <thread>

#include <Eigen/Eigenvalues>
#include <glog/logging.h>

#include "ident/discover/residual_analysis.h"
#include "ident/free_parameters.h"
#include "ident/output_error/costs.h"

namespace coaxid {
namespace {

// One cluster's residual block: its cost, where its parameter blocks sit
// among the columns, and the values to evaluate it at.
struct ClusterJob {
  std::unique_ptr<ceres::CostFunction> cost;
  std::vector<const double*> blocks;
  // Where the residual is taken, when not at `blocks` (residual_values of
  // LineariseFit): same blocks, other parameter values.
  std::vector<const double*> residual_blocks;
  std::vector<int> block_columns;  // first column of each parameter block
  std::vector<int> cluster_ends;   // residual index ending each cluster (the last = all)
  int stratum = 0;
  // Filled by Evaluate:
  bool ok = false;
  std::vector<int> columns;        // global column of each local column
  Eigen::MatrixXd normal;          // local J^T J
  std::vector<Eigen::VectorXd> gradients;  // local J^T r of each cluster
  double rss = 0;
};

// Cluster ends of a flight segment's residuals (FlightSegmentCost's order:
// rows first..end, each row's finite channels, then the continuity
// residuals, one per state, which go with the last cluster): every `rows` rows.
std::vector<int> SegmentClusterEnds(const EstimationLog& log, int first, int last, bool has_next,
                                    int rows, int num_states) {
  std::vector<int> ends;
  const int end = has_next ? last - 1 : last;
  int residuals = 0;
  for (int k = first; k <= end; ++k) {
    for (int c = 0; c < log.NumChannels(); ++c) residuals += std::isfinite(log.values(k, c));
    const bool boundary = (k - first + 1) % rows == 0 && end - k >= rows / 2;
    if (boundary && residuals > (ends.empty() ? 0 : ends.back())) ends.push_back(residuals);
  }
  if (has_next) residuals += num_states;
  if (ends.empty() || ends.back() < residuals) {
    ends.push_back(residuals);
  } else {
    ends.back() = residuals;
  }
  return ends;
}

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
  if (!job->residual_blocks.empty() &&
      (!cost.Evaluate(job->residual_blocks.data(), r.data(), nullptr) || !r.allFinite())) {
    return;
  }
  Eigen::MatrixXd J(R, width);
  int offset = 0;
  for (size_t b = 0; b < sizes.size(); ++b) {
    J.middleCols(offset, sizes[b]) = blocks[b];
    for (int k = 0; k < sizes[b]; ++k) job->columns.push_back(job->block_columns[b] + k);
    offset += sizes[b];
  }
  if (!J.allFinite()) return;
  job->normal = J.transpose() * J;
  int begin = 0;
  for (int end : job->cluster_ends) {
    job->gradients.push_back(J.middleRows(begin, end - begin).transpose() *
                             r.segment(begin, end - begin));
    begin = end;
  }
  job->rss = r.squaredNorm();
  job->ok = true;
}

}  // namespace

LinearisedFit::LinearisedFit(int num_segments, int states_per_segment,
                             std::vector<std::string> names, Eigen::VectorXd scales)
    : states_per_segment(states_per_segment),
      num_state_columns(states_per_segment * num_segments),
      parameter_names(std::move(names)),
      parameter_scales(std::move(scales)),
      state_diagonal(num_segments, StateBlock::Zero(states_per_segment, states_per_segment)),
      state_next(num_segments, StateBlock::Zero(states_per_segment, states_per_segment)),
      state_parameter(Eigen::MatrixXd::Zero(num_state_columns, parameter_names.size())),
      parameter_normal(Eigen::MatrixXd::Zero(parameter_names.size(), parameter_names.size())) {
  CHECK_EQ(parameter_scales.size(), NumParameters());
}

int LinearisedFit::ParameterIndex(const std::string& name) const {
  for (int k = 0; k < NumParameters(); ++k) {
    if (parameter_names[k] == name) return k;
  }
  return -1;
}

void LinearisedFit::AddNormal(const std::vector<int>& columns, const Eigen::MatrixXd& block) {
  const int S = num_state_columns;
  const int n = static_cast<int>(columns.size());
  CHECK_EQ(block.rows(), n);
  CHECK_EQ(block.cols(), n);
  for (int a = 0; a < n; ++a) {
    const int i = columns[a];
    for (int c = 0; c < n; ++c) {
      const int j = columns[c];
      if (i >= S && j >= S) {
        parameter_normal(i - S, j - S) += block(a, c);
      } else if (i < S && j >= S) {
        state_parameter(i, j - S) += block(a, c);
      } else if (i < S && j < S) {
        const int ns = states_per_segment;
        const int si = i / ns, sj = j / ns;
        if (si == sj) {
          state_diagonal[si](i % ns, j % ns) += block(a, c);
        } else if (sj == si + 1) {
          state_next[si](i % ns, j % ns) += block(a, c);
        } else {
          CHECK_EQ(si, sj + 1) << "a residual block couples segments " << si << " and " << sj
                               << ", which are not neighbours";
        }
      }  // the lower triangle's state-parameter and next-segment entries are the transposes
    }
  }
}

void LinearisedFit::AddCluster(const std::vector<int>& columns, const Eigen::VectorXd& block_gradient,
                               int stratum) {
  CHECK_EQ(block_gradient.size(), static_cast<int>(columns.size()));
  Cluster c;
  c.parameters = Eigen::VectorXd::Zero(NumParameters());
  int first = num_state_columns, last = -1;
  for (int j : columns) {
    if (j < num_state_columns) {
      first = std::min(first, j);
      last = std::max(last, j);
    }
  }
  c.first_state_column = last < 0 ? 0 : first;
  c.states = Eigen::VectorXd::Zero(last < 0 ? 0 : last - first + 1);
  CHECK_LE(c.states.size(), 2 * states_per_segment) << "a cluster spans more than two segments";
  for (size_t a = 0; a < columns.size(); ++a) {
    const int j = columns[a];
    if (j < num_state_columns) {
      c.states[j - first] += block_gradient[a];
    } else {
      c.parameters[j - num_state_columns] += block_gradient[a];
    }
  }
  c.stratum = stratum;
  clusters.push_back(std::move(c));
}

int ClusterRows(const EstimationLog& log, const Eigen::MatrixXd& prediction) {
  const int n = log.NumRows();
  double tau = 1;
  for (int c = 0; c < log.NumChannels(); ++c) {
    std::vector<double> r;
    for (int k = 0; k < n; ++k) {
      const double v = log.values(k, c) - prediction(k, c);
      if (std::isfinite(v)) r.push_back(v);
    }
    const int m = static_cast<int>(r.size());
    if (m < 20) continue;
    double mean = 0;
    for (double v : r) mean += v / m;
    double c0 = 0;
    for (double& v : r) {
      v -= mean;
      c0 += v * v;
    }
    if (!(c0 > 0)) continue;
    double t = 1;
    for (int l = 1; l <= std::min(200, m / 4); ++l) {
      double cl = 0;
      for (int k = l; k < m; ++k) cl += r[k] * r[k - l];
      const double rho = cl / c0;
      if (rho <= 0) break;
      t += 2 * rho;
    }
    tau = std::max(tau, t);
  }
  return std::max(10, static_cast<int>(std::ceil(3 * tau)));
}

bool LineariseFit(const Vehicle& vehicle, const std::vector<EstimationLog>& logs,
                  const std::vector<FittedSegments>& segments, const NoiseWeights& noise,
                  const std::vector<int>& cluster_rows, const OutputErrorOptions& options,
                  const std::map<std::string, double>& residual_values, LinearisedFit* out,
                  std::string* why) {
  CHECK_EQ(logs.size(), segments.size());
  CHECK_EQ(logs.size(), cluster_rows.size());
  const FreeParameters free(vehicle.parameters);
  const Eigen::VectorXd theta_scaled = free.ScaledValues();
  Eigen::VectorXd theta_residual = theta_scaled;
  for (const auto& [name, value] : residual_values) {
    const auto it = std::find(free.names().begin(), free.names().end(), name);
    CHECK(it != free.names().end()) << name << " is not free in the linearised problem";
    const int k = static_cast<int>(it - free.names().begin());
    theta_residual[k] = value / free.scales()[k];
  }
  const bool residual_elsewhere = !residual_values.empty();
  // The model's states per segment (effect states included); a fit of a
  // model without them (the declared one, linearised with a candidate that
  // owns states) gives them at rest, 0.
  const int ns = vehicle.model.NumStates();
  std::vector<FittedSegments> padded = segments;
  for (FittedSegments& s : padded) {
    for (Eigen::VectorXd& x : s.states) x = vehicle.model.StateOf(x);
  }
  int state_columns = 0;
  for (const FittedSegments& s : padded) state_columns += ns * s.starts.size();
  const int theta_column = state_columns;

  std::vector<std::unique_ptr<HeldInputPath>> paths;  // per log, shared by its segments
  for (const EstimationLog& log : logs) paths.push_back(std::make_unique<HeldInputPath>(log.inputs));
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
        if (residual_elsewhere) job.residual_blocks = {theta_residual.data()};
        job.block_columns = {theta_column};
        job.cluster_ends = {job.cost->num_residuals()};
        job.stratum = static_cast<int>(i);
        if (job.cost->num_residuals() > 0) jobs.push_back(std::move(job));
        first = end;
      }
      continue;
    }
    const FittedSegments& seg = padded[i];
    CHECK(!seg.starts.empty()) << log.source << ": a flight log needs its fitted segments";
    for (size_t j = 0; j < seg.starts.size(); ++j) {
      const bool has_next = j + 1 < seg.starts.size();
      const int last = has_next ? seg.starts[j + 1] : log.NumRows() - 1;
      ClusterJob job;
      job.cost = std::make_unique<FlightSegmentCost>(vehicle.model, free, log, seg.starts[j], last,
                                                     has_next, channel_std,
                                                     options.continuity_std, options.integrator,
                                                     paths[i].get());
      job.cluster_ends =
          SegmentClusterEnds(log, seg.starts[j], last, has_next, cluster_rows[i], ns);
      CHECK_EQ(job.cluster_ends.back(), job.cost->num_residuals());
      job.stratum = static_cast<int>(i);
      job.blocks = {seg.states[j].data(), theta_scaled.data()};
      job.block_columns = {segment_column + ns * static_cast<int>(j), theta_column};
      if (has_next) {
        job.blocks.push_back(seg.states[j + 1].data());
        job.block_columns.push_back(segment_column + ns * static_cast<int>(j + 1));
      }
      if (residual_elsewhere) {
        job.residual_blocks = job.blocks;
        job.residual_blocks[1] = theta_residual.data();
      }
      jobs.push_back(std::move(job));
    }
    // States the fit did not carry (a candidate's own, a stabilizer bar's
    // tilt) start at rest on the log's first segment and then where the
    // previous segment left them, with the residual's parameters (every
    // candidate absent: the rigid body moves as fitted), so that their
    // continuity ties hold and r stays the fit's own.
    const int given = segments[i].states.empty() ? ns : segments[i].states.front().size();
    if (given < ns) {
      const size_t first_job = jobs.size() - seg.starts.size();
      for (size_t j = 0; j + 1 < seg.starts.size(); ++j) {
        const auto* cost = static_cast<const FlightSegmentCost*>(jobs[first_job + j].cost.get());
        std::vector<Eigen::VectorXd> outputs;
        Eigen::VectorXd end_state;
        if (!cost->Predict(padded[i].states[j].data(),
                           residual_elsewhere ? theta_residual.data() : theta_scaled.data(),
                           &outputs, &end_state)) {
          *why = "the model cannot be evaluated along the fitted trajectory (CVODE failed)";
          return false;
        }
        padded[i].states[j + 1].tail(ns - given) = end_state.tail(ns - given);
      }
    }
    segment_column += ns * static_cast<int>(seg.starts.size());
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

  LinearisedFit& f = *out;
  f = LinearisedFit(state_columns / ns, ns, free.names(), free.scales());
  for (ClusterJob& job : jobs) {
    if (!job.ok) {
      *why = "the model cannot be evaluated along the fitted trajectory (CVODE failed)";
      return false;
    }
    f.AddNormal(job.columns, job.normal);
    for (const Eigen::VectorXd& gradient : job.gradients) {
      f.AddCluster(job.columns, gradient, job.stratum);
    }
    f.rss += job.rss;
    f.num_residuals += job.cost->num_residuals();
    job = ClusterJob();  // its Jacobian products are in f now
  }
  return true;
}

namespace {

// N_ss^-1 for a block-tridiagonal N_ss (LinearisedFit's state blocks) by
// block Cholesky elimination along the segments: O(segments) work and memory.
// Each diagonal block gets a ridge of 1e-10 of its own diagonal (1 where a
// column is zero: a channel no log holds), which keeps near-singular
// directions (a position no channel fixes, propagated by the ties) from
// amplifying round-off, as the dense pseudo-inverse's eigenvalue threshold did.
class BlockTridiagonalSolver {
 public:
  using Block = LinearisedFit::StateBlock;
  explicit BlockTridiagonalSolver(const LinearisedFit& fit) : fit_(fit) {
    const int S = static_cast<int>(fit.state_diagonal.size());
    const int ns = fit.states_per_segment;
    pivots_.reserve(S);
    Block previous_inverse_times_next = Block::Zero(ns, ns);  // Lambda_{j-1}^-1 N_{j-1,j}
    for (int j = 0; j < S; ++j) {
      Block lambda = fit.state_diagonal[j];
      for (int k = 0; k < ns; ++k) {
        const double d = lambda(k, k);
        lambda(k, k) += d > 0 ? 1e-10 * d : 1.0;
      }
      if (j > 0) lambda -= fit.state_next[j - 1].transpose() * previous_inverse_times_next;
      pivots_.emplace_back(lambda);
      previous_inverse_times_next = pivots_.back().solve(fit.state_next[j]);
    }
  }

  // X = N_ss^-1 B, B with num_state_columns rows.
  Eigen::MatrixXd Solve(const Eigen::MatrixXd& B) const {
    const int S = static_cast<int>(pivots_.size());
    Eigen::MatrixXd X = B;
    const int ns = fit_.states_per_segment;
    auto rows = [&X, ns](int j) { return X.middleRows(ns * j, ns); };
    for (int j = 1; j < S; ++j) {  // forward: y_j = b_j - N_j-1,j^T Lambda_j-1^-1 y_j-1
      rows(j) -= fit_.state_next[j - 1].transpose() * pivots_[j - 1].solve(rows(j - 1));
    }
    for (int j = S - 1; j >= 0; --j) {  // back: x_j = Lambda_j^-1 (y_j - N_j,j+1 x_j+1)
      Eigen::MatrixXd y = rows(j);
      if (j + 1 < S) y -= fit_.state_next[j] * rows(j + 1);
      rows(j) = pivots_[j].solve(y);
    }
    return X;
  }

 private:
  const LinearisedFit& fit_;
  std::vector<Eigen::LDLT<Block>> pivots_;
};

}  // namespace

ColumnTester::ColumnTester(const LinearisedFit& fit, const std::vector<int>& nuisance)
    : fit_(fit), nuisance_(nuisance) {
  // The states out: Y = N_ss^-1 N_s,theta, N~ = N_theta,theta - N_s,theta^T Y.
  const int P = fit.NumParameters();
  const int M = static_cast<int>(fit.clusters.size());
  Eigen::MatrixXd Y;
  if (fit.num_state_columns > 0) {
    Y = BlockTridiagonalSolver(fit).Solve(fit.state_parameter);
    reduced_normal_ = fit.parameter_normal - fit.state_parameter.transpose() * Y;
    reduced_normal_ = 0.5 * (reduced_normal_ + reduced_normal_.transpose());
    // What cancels in each diagonal entry of N~: |N_st|^T |Y|, column by column.
    state_cancellation_ =
        fit.state_parameter.cwiseAbs().cwiseProduct(Y.cwiseAbs()).colwise().sum().transpose();
  } else {
    reduced_normal_ = fit.parameter_normal;
    state_cancellation_ = Eigen::VectorXd::Zero(fit.NumParameters());
  }
  reduced_scores_.resize(P, M);
  for (int m = 0; m < M; ++m) {
    const LinearisedFit::Cluster& c = fit.clusters[m];
    reduced_scores_.col(m) = c.parameters;
    if (c.states.size() > 0) {
      reduced_scores_.col(m) -=
          Y.middleRows(c.first_state_column, c.states.size()).transpose() * c.states;
    }
  }
  const int n = static_cast<int>(nuisance.size());
  Eigen::MatrixXd A(n, n);
  for (int a = 0; a < n; ++a) {
    for (int c = 0; c < n; ++c) A(a, c) = reduced_normal_(nuisance[a], nuisance[c]);
  }
  abs_nuisance_normal_ = A.cwiseAbs();
  // Jacobi scaling by each column's own size makes the rank threshold count
  // what the states leave of it.
  inverse_scale_.resize(n);
  for (int a = 0; a < n; ++a) {
    const double d = fit.parameter_normal(nuisance[a], nuisance[a]);
    inverse_scale_[a] = d > 0 ? 1 / std::sqrt(d) : 0.0;
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
  const int M = static_cast<int>(fit_.clusters.size());
  t.q = q;
  t.clusters = M;
  if (q == 0) {
    t.why_not = "no column to test";
    return t;
  }
  // With the states already out (N~): X = N~_00^+ N~_0Z (n x q),
  // S = N~_ZZ - N~_Z0 X. NZZ, the tested columns' own N, is the yardstick.
  Eigen::MatrixXd N0Z(n, q), NZZ(q, q), reduced_ZZ(q, q);
  for (int a = 0; a < n; ++a) {
    for (int c = 0; c < q; ++c) N0Z(a, c) = reduced_normal_(nuisance_[a], tested[c]);
  }
  for (int a = 0; a < q; ++a) {
    for (int c = 0; c < q; ++c) {
      NZZ(a, c) = fit_.parameter_normal(tested[a], tested[c]);
      reduced_ZZ(a, c) = reduced_normal_(tested[a], tested[c]);
    }
  }
  const Eigen::MatrixXd X =
      inverse_scale_.asDiagonal() *
      (basis_ * (inverse_eigenvalues_.asDiagonal() *
                 (basis_.transpose() * (inverse_scale_.asDiagonal() * N0Z))));
  Eigen::MatrixXd S = reduced_ZZ - N0Z.transpose() * X;
  S = 0.5 * (S + S.transpose());
  // The tested columns must keep a part of their own after the projection,
  // as a group, beyond what rounding leaves of it. S is a difference of
  // normal-matrix products, so its diagonal carries an error of about eps
  // times the magnitudes that cancel in it: |N_ZZ|, what the states took
  // (|N_sZ|^T |Y|), the projection |N~_Z0| |X| and its solve |X|^T |N~_00| |X|.
  // A column is separable when S(c, c) stands kPrecision times above that
  // rounding floor, and the group when the smallest eigenvalue of S, scaled
  // to unit diagonal of N_ZZ, stands above the largest of the columns'
  // floors so scaled. Below it the step and the predicted drop are noise;
  // what passes it and is still absurd, the guard on the drop below catches
  // (a wind column nearly collinear on a low flight once gave wd = -71 m/s
  // and a predicted drop 20 times the RSS; not replayed). A fixed floor of
  // 1e-6 of N_ZZ(c, c), used before, also refused columns that a balance log
  // separates beside a flight log: wake_interference's weaker column kept a
  // squared sine of 3.5e-7 on seed 12962, where every candidate column's
  // floor here (kPrecision included) was 2e-12 to 1.3e-11 of its N_ZZ(c, c),
  // and its refit removed all of the balance's excess error
  // (docs/discover_confusion.md, thirty-third session).
  constexpr double kPrecision = 1e4;
  const char* kNotSeparable =
      "its regressors are explained by the parameters already estimated (not separable in "
      "these logs)";
  double group_floor = 0;  // relative to N_ZZ's diagonal
  for (int c = 0; c < q; ++c) {
    const Eigen::VectorXd x = X.col(c).cwiseAbs();
    const double cancelling = NZZ(c, c) + state_cancellation_(tested[c]) +
                              N0Z.col(c).cwiseAbs().dot(x) + x.dot(abs_nuisance_normal_ * x);
    const double floor = kPrecision * std::numeric_limits<double>::epsilon() * cancelling;
    if (!(NZZ(c, c) > 0) || !(S(c, c) > floor)) {
      t.why_not = kNotSeparable;
      return t;
    }
    group_floor = std::max(group_floor, floor / NZZ(c, c));
  }
  {
    const Eigen::VectorXd d = NZZ.diagonal().cwiseSqrt().cwiseInverse();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(d.asDiagonal() * S * d.asDiagonal(),
                                                             Eigen::EigenvaluesOnly);
    if (!(eig.eigenvalues().minCoeff() > group_floor)) {
      t.why_not = kNotSeparable;
      return t;
    }
  }
  // Projected cluster scores g_c = b~_c[Z] - X^T b~_c[0] (q x M).
  Eigen::MatrixXd g(q, M);
  Eigen::MatrixXd scores_0(n, M);
  for (int c = 0; c < q; ++c) g.row(c) = reduced_scores_.row(tested[c]);
  for (int a = 0; a < n; ++a) scores_0.row(a) = reduced_scores_.row(nuisance_[a]);
  g -= X.transpose() * scores_0;
  // C, centred within each stratum; nu from the strata that carry the score.
  std::map<int, std::vector<int>> strata;
  for (int m = 0; m < M; ++m) strata[fit_.clusters[m].stratum].push_back(m);
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(q, q);
  std::vector<std::pair<double, int>> shares;  // (trace, M_l - 1)
  for (const auto& [stratum, members] : strata) {
    const int Ml = static_cast<int>(members.size());
    if (Ml < 2) continue;
    Eigen::VectorXd mean = Eigen::VectorXd::Zero(q);
    for (int m : members) mean += g.col(m) / Ml;
    Eigen::MatrixXd Cl = Eigen::MatrixXd::Zero(q, q);
    for (int m : members) Cl += (g.col(m) - mean) * (g.col(m) - mean).transpose();
    Cl *= static_cast<double>(Ml) / (Ml - 1);
    C += Cl;
    shares.emplace_back(Cl.trace(), Ml - 1);
  }
  double nu = 0;
  for (const auto& [trace, dof] : shares) nu += trace > 0.01 * C.trace() ? dof : 0;
  if (nu < q + 1) {
    t.why_not = "too few independent clusters (" + std::to_string(M) +
                ") for a covariance of its score";
    return t;
  }
  // Sign convention: r = model - measured, so the step that lowers r^T r is -S^-1 G.
  const Eigen::VectorXd G = g.rowwise().sum();
  const Eigen::LDLT<Eigen::MatrixXd> S_ldlt(S);
  t.step = -S_ldlt.solve(G);
  t.predicted_rss_drop = G.dot(S_ldlt.solve(G));
  // The drop is the squared length of r's projection on the projected
  // columns: between 0 and r^T r, unless rounding broke the projection.
  if (!(t.predicted_rss_drop >= 0 && t.predicted_rss_drop <= fit_.rss) || !t.step.allFinite()) {
    t.why_not = std::string(kNotSeparable) + ": its linearised step is numerically unreliable";
    return t;
  }
  const Eigen::LDLT<Eigen::MatrixXd> C_ldlt(C);
  double T2;
  if (values == nullptr) {
    T2 = G.dot(C_ldlt.solve(G));
  } else {
    const Eigen::VectorXd s_delta = S * *values;
    T2 = s_delta.dot(C_ldlt.solve(s_delta));
  }
  if (!std::isfinite(T2) || C_ldlt.info() != Eigen::Success) {
    t.why_not = "the covariance of its score is singular";
    return t;
  }
  t.ok = true;
  t.statistic = std::max(0.0, T2 * (nu - q + 1) / (q * nu));
  t.p_value = FSurvival(t.statistic, q, nu - q + 1);
  t.covariance_dof = nu;
  const int dof =
      std::max(1, fit_.num_residuals - fit_.num_state_columns - static_cast<int>(nuisance_.size()) - q);
  const double sigma2 = fit_.rss / dof;
  t.white_statistic = values == nullptr ? t.predicted_rss_drop / q / sigma2
                                        : values->dot(S * *values) / q / sigma2;
  t.white_p_value = FSurvival(t.white_statistic, q, dof);
  return t;
}

std::vector<int> ParametersExcept(const LinearisedFit& fit,
                                  const std::vector<std::string>& parameters) {
  std::vector<int> out;
  for (int k = 0; k < fit.NumParameters(); ++k) {
    if (std::find(parameters.begin(), parameters.end(), fit.parameter_names[k]) == parameters.end()) {
      out.push_back(k);
    }
  }
  return out;
}

std::vector<int> ParameterIndices(const LinearisedFit& fit,
                                  const std::vector<std::string>& parameters) {
  std::vector<int> out;
  for (const std::string& name : parameters) {
    const int k = fit.ParameterIndex(name);
    CHECK_GE(k, 0) << name << " is not free in the linearised fit";
    out.push_back(k);
  }
  return out;
}

}  // namespace coaxid
