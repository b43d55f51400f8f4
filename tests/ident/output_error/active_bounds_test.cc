// The active-set solve on a box against the exact box-constrained least
// squares solution, found by enumerating every pattern of active bounds.
// Ceres' own projected solve, with the same options and starts, ended more
// than 1e-5 from that solution on 39 of these 40 draws (measured once, when
// this was written): on 17 after one iteration, at a corner where the
// projected step is zero, reported as converged.
#include "ident/output_error/active_bounds.h"

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>

namespace coaxid {
namespace {

constexpr int kRows = 12, kCols = 4;

// r = A x - b.
class LinearResiduals : public ceres::SizedCostFunction<kRows, kCols> {
 public:
  LinearResiduals(Eigen::MatrixXd a, Eigen::VectorXd b) : a_(std::move(a)), b_(std::move(b)) {}
  bool Evaluate(double const* const* x, double* r, double** jacobians) const override {
    const Eigen::Map<const Eigen::VectorXd> xv(x[0], kCols);
    Eigen::Map<Eigen::VectorXd>(r, kRows) = a_ * xv - b_;
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, kRows, kCols, Eigen::RowMajor>> jacobian(jacobians[0]);
      jacobian = a_;
    }
    return true;
  }

 private:
  Eigen::MatrixXd a_;
  Eigen::VectorXd b_;
};

// min |A x - b|^2 on the box, by trying every pattern of coordinates held at
// their lower or upper bound (3^n), solving for the rest, and keeping the
// lowest feasible cost. The problem is convex, so that is the minimum.
Eigen::VectorXd EnumeratedSolution(const Eigen::MatrixXd& a, const Eigen::VectorXd& b,
                                   const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  const int n = static_cast<int>(lower.size());
  int patterns = 1;
  for (int i = 0; i < n; ++i) patterns *= 3;
  double best = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_x;
  for (int p = 0; p < patterns; ++p) {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
    std::vector<int> free;
    for (int i = 0, code = p; i < n; ++i, code /= 3) {
      if (code % 3 == 0) free.push_back(i);
      if (code % 3 == 1) x[i] = lower[i];
      if (code % 3 == 2) x[i] = upper[i];
    }
    Eigen::VectorXd rhs = b - a * x;
    Eigen::MatrixXd af(a.rows(), free.size());
    for (size_t k = 0; k < free.size(); ++k) af.col(k) = a.col(free[k]);
    if (!free.empty()) {
      const Eigen::VectorXd xf = af.colPivHouseholderQr().solve(rhs);
      for (size_t k = 0; k < free.size(); ++k) x[free[k]] = xf[k];
    }
    if ((x.array() < lower.array() - 1e-12).any() || (x.array() > upper.array() + 1e-12).any()) {
      continue;
    }
    const double cost = (a * x - b).squaredNorm();
    if (cost < best) {
      best = cost;
      best_x = x;
    }
  }
  return best_x;
}

// A random problem with strongly correlated columns (a long, narrow valley,
// where a projected step loses most of its predicted decrease), a random box
// around the origin and a random start inside it.
struct BoxDraw {
  Eigen::MatrixXd a;
  Eigen::VectorXd b, lower, upper, start;
};

BoxDraw Draw(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(0.2, 1.5);
  BoxDraw d;
  d.a.resize(kRows, kCols);
  const Eigen::VectorXd common = Eigen::VectorXd::NullaryExpr(kRows, [&] { return normal(rng); });
  for (int j = 0; j < kCols; ++j) {
    for (int i = 0; i < kRows; ++i) d.a(i, j) = common[i] + 0.1 * normal(rng);
  }
  d.b = Eigen::VectorXd::NullaryExpr(kRows, [&] { return 3 * normal(rng); });
  d.lower.resize(kCols);
  d.upper.resize(kCols);
  d.start.resize(kCols);
  for (int i = 0; i < kCols; ++i) {
    d.lower[i] = -uniform(rng);
    d.upper[i] = uniform(rng);
    const double x = d.lower[i] + (d.upper[i] - d.lower[i]) * (0.5 + 0.4 * normal(rng) / 3);
    d.start[i] = std::min(std::max(x, d.lower[i]), d.upper[i]);
  }
  return d;
}

// Solves the draw from its start with `max_iterations`; *x gets the solution.
BoundedSolveSummary Solve(const BoxDraw& d, int max_iterations, Eigen::VectorXd* x,
                          const std::vector<int>& start_held = {}) {
  *x = d.start;
  ceres::Problem problem;
  problem.AddResidualBlock(new LinearResiduals(d.a, d.b), nullptr, x->data());
  for (int i = 0; i < kCols; ++i) {
    problem.SetParameterLowerBound(x->data(), i, d.lower[i]);
    problem.SetParameterUpperBound(x->data(), i, d.upper[i]);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = max_iterations;
  options.function_tolerance = 1e-15;
  options.parameter_tolerance = 1e-15;
  options.gradient_tolerance = 1e-15;
  const BoundedSolveSummary s =
      SolveHoldingActiveBounds(options, &problem, x->data(), d.lower, d.upper, start_held);
  EXPECT_FALSE(problem.HasManifold(x->data()));  // the block is left as it was given
  return s;
}

TEST(SolveHoldingActiveBounds, FindsTheBoxConstrainedLeastSquaresSolution) {
  int with_held = 0, with_release = 0;
  for (unsigned seed = 1; seed <= 40; ++seed) {
    const BoxDraw d = Draw(seed);
    Eigen::VectorXd x;
    const BoundedSolveSummary s = Solve(d, 200, &x);
    const Eigen::VectorXd truth = EnumeratedSolution(d.a, d.b, d.lower, d.upper);
    ASSERT_EQ(truth.size(), kCols);
    // The valley's narrow direction has curvature ~1e-2 of the wide one: a
    // cost converged to 1e-15 leaves the position good to about 1e-6.
    EXPECT_LT((x - truth).lpNorm<Eigen::Infinity>(), 1e-5) << "seed " << seed;
    EXPECT_FALSE(s.hit_iteration_limit) << "seed " << seed;
    for (int i : s.held) {
      EXPECT_TRUE(x[i] == d.lower[i] || x[i] == d.upper[i]) << "seed " << seed;
      EXPECT_TRUE(truth[i] == d.lower[i] || truth[i] == d.upper[i]) << "seed " << seed;
    }
    with_held += !s.held.empty();
    with_release += !s.released.empty();
  }
  // The draws exercise both halves of the active set: holding, and releasing
  // a coordinate whose multiplier turned out to have the wrong sign.
  EXPECT_GT(with_held, 0);
  EXPECT_GT(with_release, 0);
}

TEST(SolveHoldingActiveBounds, ReleasesAWrongStartingActiveSet) {
  // A continuation's start: a random corner of the box with every
  // coordinate held, and a held coordinate that is not at a bound (ignored).
  // Whatever of that guess is wrong must be released on the way to the
  // solution. 2000 draws (0.4 s): the first version stopped short on 2 of
  // them (seeds 694, 961), out of solves after 4 releases and their holds;
  // one before it on seed 33, from a trust region carried past a release.
  int released = 0;
  for (unsigned seed = 1; seed <= 2000; ++seed) {
    BoxDraw d = Draw(seed);
    std::mt19937 rng(1000 + seed);
    for (int i = 0; i < kCols; ++i) d.start[i] = (rng() % 2) ? d.lower[i] : d.upper[i];
    d.start[kCols - 1] = 0.5 * (d.lower[kCols - 1] + d.upper[kCols - 1]);
    const Eigen::VectorXd truth = EnumeratedSolution(d.a, d.b, d.lower, d.upper);
    Eigen::VectorXd x;
    const BoundedSolveSummary s = Solve(d, 200, &x, {0, 1, 2, 3});
    EXPECT_LT((x - truth).lpNorm<Eigen::Infinity>(), 1e-5) << "seed " << seed;
    EXPECT_FALSE(s.hit_iteration_limit) << "seed " << seed;
    released += static_cast<int>(s.released.size());
  }
  EXPECT_GT(released, 2000);  // most corners hold more than one wrong bound
}

TEST(SolveHoldingActiveBounds, ClaimsConvergenceOnlyAtTheSolutionAndKeepsToItsBudget) {
  // Short budgets: every solve either reports the budget spent, or is at
  // the solution; none takes more iterations than it was given.
  int short_of_it = 0;
  for (unsigned seed = 1; seed <= 40; ++seed) {
    const BoxDraw d = Draw(seed);
    const Eigen::VectorXd truth = EnumeratedSolution(d.a, d.b, d.lower, d.upper);
    for (int budget : {1, 2, 4, 8}) {
      Eigen::VectorXd x;
      const BoundedSolveSummary s = Solve(d, budget, &x);
      EXPECT_LE(s.iterations, budget) << "seed " << seed;
      if (s.hit_iteration_limit) {
        ++short_of_it;
        EXPECT_NE(s.message.find("Maximum number of iterations"), std::string::npos) << s.message;
      } else {
        EXPECT_LT((x - truth).lpNorm<Eigen::Infinity>(), 1e-5)
            << "seed " << seed << ", budget " << budget;
      }
    }
  }
  EXPECT_GT(short_of_it, 0);
}

}  // namespace
}  // namespace coaxid
