// Levenberg-Marquardt on a box, with the coordinates that press on their
// bounds held there (an active set).
//
// Ceres handles bounds by projecting each trust-region step onto the box.
// Once the solution presses on a bound, the projected step no longer earns
// the decrease the Gauss-Newton model predicts for the unprojected one: the
// ratio of actual to predicted decrease sits near 0.1-0.25, the trust region
// shrinks on every successful step, and the solve crawls (measured on
// bench/ident/discover/discover_flight_only_bench, ground effect: the
// declared fit with Cz at its upper bound, 20 successful iterations with the
// step shrinking from 1.6e-2 to 1.8e-4 and the cost still falling at its
// cap). Worse, a projected step can vanish at a corner of the box that is
// not a minimum, and Ceres reports that as converged (active_bounds_test:
// 39 of 40 random boxes ended away from the solution).
//
// Here a solve stops as soon as a coordinate has sat at a bound after two
// successful steps in a row; that coordinate is then held at its bound (a
// ceres::SubsetManifold) and the rest solved freely, on what is left of the
// iteration budget and from the trust region the last solve reached.
// When a solve converges, the Karush-Kuhn-Tucker conditions are checked
// with every coordinate free: a coordinate at a bound whose cost falls
// outward is held too, and of the held ones whose cost falls inward (a
// Lagrange multiplier of the wrong sign) the fastest is released; the solve
// goes on until neither happens.
//
// A solve can start with coordinates held (`start_held`): a continuation of
// a solve that ended with them held, which would otherwise find them again
// in failed and projected steps.
#pragma once

#include <ceres/problem.h>
#include <ceres/solver.h>

#include <Eigen/Core>
#include <string>
#include <vector>

namespace coaxid {

struct BoundedSolveSummary {
  ceres::Solver::Summary last;  // the last of the solves
  std::string message;          // Ceres' message of the last solve, or that the budget ran out
  int solves = 0;
  int iterations = 0;  // over all solves
  double initial_cost = 0, final_cost = 0;
  int residual_evaluations = 0, jacobian_evaluations = 0;
  double residual_seconds = 0, jacobian_seconds = 0, linear_solver_seconds = 0, solve_seconds = 0;
  // The iteration budget ran out before a solve converged.
  bool hit_iteration_limit = false;
  std::vector<int> held;      // coordinates of the block held at a bound at the end
  std::vector<int> released;  // held during the call, then released
};

// Solves `problem` like ceres::Solve(options, ...), with options.max_num_iterations
// the budget of all its solves together. `block` (size lower.size()) is the
// bounded parameter block, with no manifold of its own; lower and upper are
// its bounds (infinite: none), as set on the problem. Coordinates in
// `start_held` that sit at a bound start held (the others are ignored).
// Leaves the block without a manifold.
BoundedSolveSummary SolveHoldingActiveBounds(ceres::Solver::Options options,
                                             ceres::Problem* problem, double* block,
                                             const Eigen::VectorXd& lower,
                                             const Eigen::VectorXd& upper,
                                             const std::vector<int>& start_held = {});

}  // namespace coaxid
