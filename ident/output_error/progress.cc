#include "ident/output_error/progress.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "core/stopwatch.h"

namespace coaxid {

int IterationsLeftAtLinearRate(double previous_drop, double drop, double cost,
                               double function_tolerance) {
  if (!(drop > 0 && cost > 0 && function_tolerance > 0)) return -1;
  const double stop = function_tolerance * cost;
  if (drop < stop) return 0;
  if (!(previous_drop > 0)) return -1;
  const double rho = drop / previous_drop;
  if (!(rho < 1)) return -1;
  // The first n with drop rho^n < stop: n > log(stop / drop) / log(rho).
  return static_cast<int>(std::floor(std::log(stop / drop) / std::log(rho))) + 1;
}

OutputErrorProgress::OutputErrorProgress(std::function<void(const std::string&)> print,
                                         std::string stage,
                                         std::chrono::steady_clock::time_point start, long rows,
                                         double function_tolerance)
    : print_(std::move(print)),
      stage_(std::move(stage)),
      start_(start),
      rows_(rows),
      function_tolerance_(function_tolerance) {}

ceres::CallbackReturnType OutputErrorProgress::operator()(const ceres::IterationSummary& s) {
  const double drop = s.step_is_successful ? s.cost_change : 0.0;  // Ceres: old - new cost
  const int left =
      s.iteration > 0 ? IterationsLeftAtLinearRate(previous_drop_, drop, s.cost,
                                                   function_tolerance_)
                      : -1;
  if (s.iteration > 0 && s.step_is_successful) previous_drop_ = drop;
  if (!print_) return ceres::SOLVER_CONTINUE;
  char line[320];
  // A trial point the model could not be evaluated at (an integration that
  // failed, a non-finite state): Ceres reports its cost as the largest
  // double, and its ratio as -1.8e308, which %.2f would print in 300 digits.
  const bool evaluated = s.cost < std::numeric_limits<double>::max();
  char cost[64];
  if (evaluated) {
    std::snprintf(cost, sizeof cost, "cost %.6e", s.cost);
  } else {
    std::snprintf(cost, sizeof cost, "the model failed at the trial point");
  }
  int n = std::snprintf(line, sizeof line,
                        "%s: iteration %2d  %s  |step| %.2e  tr_radius %.1e  tr_ratio %.2f  "
                        "elapsed %.1f s  (%.1f s, %.0f rows/s)",
                        stage_.c_str(), s.iteration, cost, s.step_norm, s.trust_region_radius,
                        evaluated ? s.relative_decrease : -INFINITY, SecondsSince(start_),
                        s.iteration_time_in_seconds,
                        rows_ / std::max(s.iteration_time_in_seconds, 1e-9));
  if (left > 0 && n > 0 && n < static_cast<int>(sizeof line)) {
    std::snprintf(line + n, sizeof line - n,
                  "  about %d more iteration(s), %.0f s, in this stage at this rate", left,
                  left * s.iteration_time_in_seconds);
  }
  print_(line);
  return ceres::SOLVER_CONTINUE;
}

}  // namespace coaxid
