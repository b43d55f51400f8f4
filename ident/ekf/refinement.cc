#include "ident/ekf/refinement.h"

#include <cmath>
#include <cstdio>
#include <utility>

namespace coaxid {
namespace {

// Each parameter's straight step within the bounds, in its std at p.
Eigen::VectorXd StepInStd(const Eigen::VectorXd& p, const PassResult& at,
                          const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  const int np = static_cast<int>(p.size());
  const Eigen::VectorXd to = (p + at.step).cwiseMax(lower).cwiseMin(upper);
  const Eigen::VectorXd sd = at.P.diagonal().tail(np).cwiseMax(1e-300).cwiseSqrt();
  return (to - p).cwiseQuotient(sd);
}

double Largest(const Eigen::VectorXd& v) { return v.size() > 0 ? v.cwiseAbs().maxCoeff() : 0.0; }

}  // namespace

Eigen::VectorXd SteppedParameters(const Eigen::VectorXd& p, const Eigen::VectorXd& step,
                                  double lambda, const Eigen::VectorXd& lower,
                                  const Eigen::VectorXd& upper) {
  Eigen::VectorXd to = p + lambda * step;
  for (int k = 0; k < p.size(); ++k) {
    const bool keeps_sign = (lower[k] >= 0 && p[k] > 0) || (upper[k] <= 0 && p[k] < 0);
    if (keeps_sign) to[k] = p[k] * std::exp(lambda * step[k] / p[k]);
  }
  return to.cwiseMax(lower).cwiseMin(upper);
}

Refinement Refine(const Eigen::VectorXd& p, const PassResult& at, const EkfOptions& options,
                  const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                  const std::function<PassResult(const Eigen::VectorXd&)>& frozen_pass) {
  Refinement r{p, at};
  const double tolerance = options.refine_tolerance_std;
  double largest = Largest(StepInStd(r.p, r.at_p, lower, upper));
  r.step_std_at_start = largest;
  for (;;) {
    if (largest <= tolerance) {
      r.stop = "no parameter's step exceeds the tolerance";
      break;
    }
    if (r.steps == options.max_refinements) {
      r.stop = "the refinements allowed are spent";
      r.converged = false;
      break;
    }
    bool rose = false;
    for (double lambda = 1; !rose && lambda * largest > tolerance; lambda /= 2) {
      const Eigen::VectorXd to = SteppedParameters(r.p, r.at_p.step, lambda, lower, upper);
      PassResult trial = frozen_pass(to);
      if (trial.ok && trial.log_likelihood > r.at_p.log_likelihood) {
        r.p = to;
        r.at_p = std::move(trial);
        rose = true;
      }
    }
    if (!rose) {
      r.stop = "the likelihood does not rise along the step";
      r.converged = largest <= options.unconverged_step_std;
      break;
    }
    ++r.steps;
    largest = Largest(StepInStd(r.p, r.at_p, lower, upper));
  }
  r.step_std = largest;
  return r;
}

std::string LargeSteps(const Eigen::VectorXd& p, const PassResult& at, double tolerance,
                       const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                       const std::vector<std::string>& names) {
  const Eigen::VectorXd in_std = StepInStd(p, at, lower, upper);
  std::string out;
  for (int k = 0; k < in_std.size(); ++k) {
    if (std::fabs(in_std[k]) <= tolerance) continue;
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "%s%s %+.1f std", out.empty() ? "" : ", ",
                  names[k].c_str(), in_std[k]);
    out += buffer;
  }
  return out;
}

}  // namespace coaxid
