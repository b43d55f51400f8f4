#include "ident/output_error/active_bounds.h"

#include <ceres/iteration_callback.h>
#include <ceres/manifold.h>

#include <algorithm>
#include <cmath>

namespace coaxid {
namespace {

constexpr char kBudgetSpent[] =
    "Maximum number of iterations reached, with parameters held at their bounds.";
constexpr char kActiveSetUnsettled[] =
    "Maximum number of solves reached: the parameters held at their bounds kept changing.";

bool AtBound(double x, double bound) {
  return std::isfinite(bound) && std::abs(x - bound) <= 1e-12 * (1 + std::abs(bound));
}

bool AtEitherBound(const double* block, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                   int i) {
  return AtBound(block[i], lower[i]) || AtBound(block[i], upper[i]);
}

// Stops the solve once the same coordinates (among `watched`) have sat at a
// bound after two successful steps in a row (the start counts as one).
class PressingOnBounds : public ceres::IterationCallback {
 public:
  PressingOnBounds(const double* block, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                   std::vector<bool> watched)
      : block_(block), lower_(lower), upper_(upper), watched_(std::move(watched)) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (!s.step_is_successful) return ceres::SOLVER_CONTINUE;  // the state did not move
    std::vector<int> at;
    for (int i = 0; i < lower_.size(); ++i) {
      if (watched_[i] && AtEitherBound(block_, lower_, upper_, i)) at.push_back(i);
    }
    if (at.empty() || at != last_) {
      streak_ = at.empty() ? 0 : 1;
      last_ = at;
      return ceres::SOLVER_CONTINUE;
    }
    if (++streak_ < 2) return ceres::SOLVER_CONTINUE;
    pressing_ = at;
    return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
  }

  const std::vector<int>& pressing() const { return pressing_; }

 private:
  const double* block_;
  const Eigen::VectorXd& lower_;
  const Eigen::VectorXd& upper_;
  std::vector<bool> watched_;
  std::vector<int> last_, pressing_;
  int streak_ = 0;
};

void HoldCoordinates(ceres::Problem* problem, double* block, const std::vector<bool>& held) {
  std::vector<int> constant;
  for (size_t i = 0; i < held.size(); ++i) {
    if (held[i]) constant.push_back(static_cast<int>(i));
  }
  problem->SetParameterBlockVariable(block);
  if (constant.empty()) {
    problem->SetManifold(block, nullptr);
  } else if (constant.size() == held.size()) {
    problem->SetManifold(block, nullptr);
    problem->SetParameterBlockConstant(block);
  } else {
    problem->SetManifold(block, new ceres::SubsetManifold(static_cast<int>(held.size()), constant));
  }
}

// d cost / d block at the block's present values, every coordinate free.
bool Gradient(ceres::Problem* problem, double* block, std::vector<double>* gradient) {
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = {block};
  double cost = 0;
  return problem->Evaluate(eo, &cost, nullptr, gradient, nullptr);
}

}  // namespace

BoundedSolveSummary SolveHoldingActiveBounds(ceres::Solver::Options options,
                                             ceres::Problem* problem, double* block,
                                             const Eigen::VectorXd& lower,
                                             const Eigen::VectorXd& upper,
                                             const std::vector<int>& start_held) {
  const int n = static_cast<int>(lower.size());
  const int budget = options.max_num_iterations;
  const double caller_radius = options.initial_trust_region_radius;
  const std::vector<ceres::IterationCallback*> callbacks = options.callbacks;
  options.update_state_every_iteration = true;  // the watch reads the accepted state
  std::vector<bool> held(n, false), released(n, false);
  for (int i : start_held) {
    if (i >= 0 && i < n && AtEitherBound(block, lower, upper, i)) held[i] = true;
  }
  BoundedSolveSummary out;
  // Each pass either holds more coordinates or releases one; the bound on
  // passes only guards against cycling between the two. A start that holds
  // every coordinate wrongly needs n releases, each of which may meet a
  // bound on its way (a hold): about 2n + 1 solves (active_bounds_test: 2
  // of 2000 draws with n = 4 needed 13, beyond the 2n + 4 this bound was).
  const int max_solves = 4 * n + 8;
  while (true) {
    if (out.solves == max_solves) {
      out.hit_iteration_limit = true;  // the set kept changing: not shown to be an optimum
      out.message = kActiveSetUnsettled;
      break;
    }
    std::vector<bool> watched(n);
    for (int i = 0; i < n; ++i) watched[i] = !held[i];
    PressingOnBounds watch(block, lower, upper, watched);
    options.callbacks = callbacks;
    options.callbacks.push_back(&watch);
    options.max_num_iterations = std::max(0, budget - out.iterations);
    HoldCoordinates(problem, block, held);
    ceres::Solver::Summary s;
    ceres::Solve(options, problem, &s);
    if (out.solves++ == 0) out.initial_cost = s.initial_cost;
    out.final_cost = s.final_cost;
    out.iterations += s.iterations.empty() ? 0 : static_cast<int>(s.iterations.size()) - 1;
    out.residual_evaluations += s.num_residual_evaluations;
    out.jacobian_evaluations += s.num_jacobian_evaluations;
    out.residual_seconds += s.residual_evaluation_time_in_seconds;
    out.jacobian_seconds += s.jacobian_evaluation_time_in_seconds;
    out.linear_solver_seconds += s.linear_solver_time_in_seconds;
    out.solve_seconds += s.total_time_in_seconds;
    out.last = s;
    out.message = s.message;
    out.hit_iteration_limit = s.termination_type == ceres::NO_CONVERGENCE;
    if (s.termination_type == ceres::FAILURE || !s.IsSolutionUsable()) break;
    if (s.termination_type == ceres::USER_SUCCESS && !watch.pressing().empty()) {
      // Go on from the trust region this solve reached (after two
      // successful steps), not from Ceres' default (1e4), which the next
      // solve would first shrink in failed steps.
      if (!s.iterations.empty()) {
        options.initial_trust_region_radius =
            std::min(options.max_trust_region_radius, s.iterations.back().trust_region_radius);
      }
      for (int i : watch.pressing()) held[i] = true;
      if (out.iterations >= budget) {
        out.hit_iteration_limit = true;  // stopped short of an optimum
        out.message = kBudgetSpent;
        break;
      }
      continue;
    }
    if (out.hit_iteration_limit) break;
    // Converged: the Karush-Kuhn-Tucker conditions at the bounds, from the
    // gradient with every coordinate free. A coordinate at a bound whose
    // cost falls outward is held (a projected step can stall on such a
    // corner with a zero step, which Ceres reports as converged); of the
    // held coordinates whose cost falls inward (a multiplier of the wrong
    // sign), the one falling fastest is released. Gradients below the
    // threshold are noise: moving 1e-3 of the scaled coordinate would lower
    // the cost by less than the solve's own stop on the cost.
    // Nothing at a bound (held ones always are): nothing to check, and no
    // gradient evaluation spent on it.
    bool any_at_bound = false;
    for (int i = 0; i < n; ++i)
      any_at_bound = any_at_bound || AtEitherBound(block, lower, upper, i);
    if (!any_at_bound) break;
    HoldCoordinates(problem, block, std::vector<bool>(n, false));
    std::vector<double> g;
    if (!Gradient(problem, block, &g)) break;
    const double threshold = 1e3 * options.function_tolerance * std::max(out.final_cost, 1e-300);
    bool changed = false;
    int release = -1;
    double fastest = threshold;
    for (int i = 0; i < n; ++i) {
      if (!AtEitherBound(block, lower, upper, i)) continue;
      const bool at_lower = AtBound(block[i], lower[i]);
      const double inward = at_lower ? -g[i] : g[i];  // the cost's fall per unit inward
      if (!held[i] && -inward > threshold) {
        held[i] = true;
        changed = true;
      } else if (held[i] && inward > fastest) {
        fastest = inward;
        release = i;
      }
    }
    if (!changed && release >= 0) {
      held[release] = false;
      released[release] = true;
      changed = true;
    }
    if (!changed) break;
    // A converged solve's trust region may have shrunk in failed steps at
    // the cost's noise level; carried into the changed problem, a tiny one
    // stops the next solve on the function tolerance after steps too short
    // to move (measured: active_bounds_test, a released coordinate left
    // 9e-4 from its optimum). The next solve starts from the caller's.
    options.initial_trust_region_radius = caller_radius;
    if (out.iterations >= budget) {
      out.hit_iteration_limit = true;  // not at an optimum, and no iterations left
      out.message = kBudgetSpent;
      break;
    }
  }
  for (int i = 0; i < n; ++i) {
    if (held[i]) out.held.push_back(i);
    if (released[i]) out.released.push_back(i);
  }
  HoldCoordinates(problem, block, std::vector<bool>(n, false));
  return out;
}

}  // namespace coaxid
