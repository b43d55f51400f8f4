// The output-error fit's progress lines (one per Ceres iteration, on stderr
// through OutputErrorOptions::progress): cost, step, the trust region's
// radius and its ratio of actual to predicted cost decrease (Ceres'
// tr_radius and tr_ratio: a ratio that stays well below 1 while the radius
// stays wide open is a Gauss-Newton model that keeps overrating its steps,
// the crawl of a fit along a misfit), elapsed time, rows per
// second, and the time the stage has left at its present rate of convergence.
#pragma once

#include <chrono>
#include <functional>
#include <string>

#include <ceres/iteration_callback.h>

namespace coaxid {

// Iterations a solve has left before Ceres' stop on the relative cost change
// (|drop| / cost < function_tolerance), if the cost keeps falling at the
// present linear rate rho = drop / previous_drop: the first n with
// drop rho^n < function_tolerance cost, n = floor(log(tol cost / drop) / log rho) + 1.
// 0 when the last drop already meets the stop; -1 when no rate is known
// (a first iteration, a rise, or rho >= 1). Gauss-Newton near its minimum
// converges faster than linearly, so this errs long.
int IterationsLeftAtLinearRate(double previous_drop, double drop, double cost,
                               double function_tolerance);

class OutputErrorProgress : public ceres::IterationCallback {
 public:
  // rows: the logs' rows, each simulated (with sensitivities) once an iteration.
  OutputErrorProgress(std::function<void(const std::string&)> print, std::string stage,
                      std::chrono::steady_clock::time_point start, long rows,
                      double function_tolerance);
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override;

 private:
  std::function<void(const std::string&)> print_;
  std::string stage_;
  std::chrono::steady_clock::time_point start_;
  long rows_;
  double function_tolerance_;
  double previous_drop_ = 0;
};

}  // namespace coaxid
