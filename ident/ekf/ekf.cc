#include "ident/ekf/ekf.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <utility>

#include <Eigen/Cholesky>
#include <glog/logging.h>

#include "core/errors.h"
#include "core/report_values.h"
#include "dynamics/outputs.h"
#include "ident/ekf/history_sink.h"
#include "ident/ekf/pass.h"
#include "ident/ekf/refinement.h"
#include "ident/free_parameters.h"

namespace coaxid {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// Inverse of the standard normal CDF (Acklam's rational approximation,
// relative error < 1.2e-9).
double NormalQuantile(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,
                             -2.759285104469687e+02, 1.383577518672690e+02,
                             -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02,
                             -1.556989798598866e+02, 6.680131188771972e+01,
                             -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01,
                             -2.400758277161838e+00, -2.549732539343734e+00,
                             4.374664141464968e+00,  2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01,
                             2.445134137142996e+00, 3.754408661907416e+00};
  const double low = 0.02425;
  if (p < low) {
    const double q = std::sqrt(-2 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1);
  }
  if (p > 1 - low) return -NormalQuantile(1 - p);
  const double q = p - 0.5, r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1);
}

}  // namespace

std::pair<double, double> ChiSquareMeanBand(double dof, double confidence) {
  if (!(dof > 0)) return {0.0, std::numeric_limits<double>::infinity()};
  const double z = NormalQuantile(0.5 + 0.5 * confidence);
  const double c = 2.0 / (9.0 * dof);
  auto quantile = [&](double zp) {
    const double base = std::max(0.0, 1 - c + zp * std::sqrt(c));
    return base * base * base;  // chi2_p(k) / k
  };
  return {quantile(-z), quantile(z)};
}

double InnovationGateThreshold(double probability) {
  const double z = NormalQuantile(0.5 * probability);  // chi2(1) = z^2, two-sided tail
  return z * z;
}

bool EkfOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  for (int i = 0; i < kNumStates; ++i) {
    if (!(state_psd[i] >= 0 && std::isfinite(state_psd[i]))) {
      return fail(std::string("state_psd of ") + StateName(i) + " must be finite and >= 0");
    }
  }
  if (!(effect_state_psd >= 0 && std::isfinite(effect_state_psd))) {
    return fail("effect_state_psd must be finite and >= 0");
  }
  if (!(parameter_psd >= 0 && std::isfinite(parameter_psd))) {
    return fail("parameter_psd must be finite and >= 0");
  }
  for (const auto& [name, q] : parameter_psd_by_name) {
    if (!(q >= 0 && std::isfinite(q))) return fail("parameter_psd of " + name + " must be >= 0");
  }
  if (!(initial_parameter_std > 0 && std::isfinite(initial_parameter_std))) {
    return fail("initial_parameter_std must be finite and > 0");
  }
  for (const auto& [name, s] : initial_parameter_std_by_name) {
    if (!(s > 0 && std::isfinite(s))) return fail("initial std of " + name + " must be > 0");
  }
  for (double s : {initial_position_std, initial_velocity_std, initial_angle_std,
                   initial_rate_std, initial_effect_state_std}) {
    if (!(s > 0 && std::isfinite(s))) return fail("initial state std values must be > 0");
  }
  if (!(max_substep_s > 0 && std::isfinite(max_substep_s))) {
    return fail("max_substep_s must be finite and > 0");
  }
  std::string integrator_why;
  if (!integrator.IsValid(&integrator_why)) return fail("integrator: " + integrator_why);
  if (!(nis_burn_in_s >= 0)) return fail("nis_burn_in_s must be >= 0");
  if (!(divergence_nis > 1)) return fail("divergence_nis must be > 1");
  if (!(divergence_window_s > 0)) return fail("divergence_window_s must be > 0");
  if (!(undetermined_variance_ratio > 0 && undetermined_variance_ratio < 1)) {
    return fail("undetermined_variance_ratio must lie in (0, 1)");
  }
  if (max_refinements < 0) return fail("max_refinements must be >= 0");
  if (!(unconverged_step_std >= refine_tolerance_std && std::isfinite(unconverged_step_std))) {
    return fail("unconverged_step_std must be finite and >= refine_tolerance_std");
  }
  if (!(refine_tolerance_std > 0 && std::isfinite(refine_tolerance_std))) {
    return fail("refine_tolerance_std must be finite and > 0");
  }
  if (progress_every_rows < 1) return fail("progress_every_rows must be >= 1");
  if (smoother_block_rows < 0) return fail("smoother_block_rows must be >= 0 (0: automatic)");
  if (!(gate_probability >= 0 && gate_probability < 1)) {
    return fail("gate_probability must lie in [0, 1) (0: no innovation gate)");
  }
  if (!(gate_max_s > 0)) return fail("gate_max_s must be > 0");
  if (noise_adaptations < 0 || noise_adaptations > 5) {
    return fail("noise_adaptations must lie in 0 .. 5");
  }
  if (noise_adaptation_rows < 0) return fail("noise_adaptation_rows must be >= 0 (0: all)");
  return true;
}


EkfResult RunEkf(const Vehicle& vehicle, const std::vector<EstimationLog>& logs,
                 const NoiseWeights& noise, const EkfOptions& options,
                 EkfHistorySink* history) {
  const Clock::time_point start = Clock::now();
  std::string why;
  if (!options.IsValid(&why)) throw InputError("EKF options: " + why);
  if (logs.empty()) throw InputError("EKF: no log to estimate from");
  long rows_per_pass = 0;
  for (const EstimationLog& log : logs) {
    if (log.kind != LogKind::kFlight) {
      throw InputError(log.source + ": a " + LogKindName(log.kind) +
                       " log; the EKF estimates from flight logs (states and parameters "
                       "together); balance logs are for linear_kf and output_error");
    }
    if (log.NumRows() < 2) throw InputError(log.source + ": fewer than two rows");
    for (const std::string& name : log.channel_names) {
      auto it = noise.std.find(name);
      if (it == noise.std.end() || !(it->second > 0 && std::isfinite(it->second))) {
        throw InputError(log.source + ": no positive measurement noise level for channel " +
                         name);
      }
    }
    rows_per_pass += log.NumRows();
  }
  for (const auto* by_name :
       {&options.parameter_psd_by_name, &options.initial_parameter_std_by_name}) {
    for (const auto& entry : *by_name) {
      if (!vehicle.parameters.Has(entry.first)) {
        throw InputError("EKF options name an unknown parameter '" + entry.first + "'");
      }
    }
  }

  EkfResult result;
  result.parameters = vehicle.parameters;

  // Scale (model.md, decision 8; ident/scale_gauge.h): an initial std given
  // by name is a prior.
  std::vector<std::string> prior_names;
  for (const auto& entry : options.initial_parameter_std_by_name) {
    prior_names.push_back(entry.first);
  }
  result.gauge = FixScaleGauge(vehicle.model, logs, prior_names, options.scale_anchor,
                               &result.parameters);
  if (!result.gauge.note.empty()) result.notes.push_back(result.gauge.note);

  const FreeParameters free(result.parameters);
  const int np = free.size();
  result.free_names = free.names();
  result.free_indices = free.indices();
  result.scales = free.scales();
  // Nothing to linearise differently without free parameters.
  const bool covariance_pass = options.covariance_pass && np > 0;
  result.covariance_pass = covariance_pass;

  // The parameter set of the passes: the anchor's `estimated` flag applied.
  Vehicle anchored = vehicle;
  anchored.parameters = result.parameters;
  EkfProblem problem{anchored, logs, noise, options, free, free.ScaledLower(), free.ScaledUpper(),
                  Eigen::VectorXd(), Eigen::MatrixXd(), EkfState()};
  const Eigen::VectorXd p0 = free.ScaledValues();
  for (int k = 0; k < np; ++k) {
    if (!(p0[k] >= problem.lower[k] && p0[k] <= problem.upper[k])) {
      throw InputError("initial value of " + free.names()[k] + " lies outside its bounds");
    }
  }
  Eigen::VectorXd prior_std(np);
  problem.qp.resize(np);
  for (int k = 0; k < np; ++k) {
    const std::string& name = free.names()[k];
    auto s = options.initial_parameter_std_by_name.find(name);
    prior_std[k] = s != options.initial_parameter_std_by_name.end()
                       ? s->second / free.scales()[k]
                       : options.initial_parameter_std;
    auto q = options.parameter_psd_by_name.find(name);
    problem.qp[k] = q != options.parameter_psd_by_name.end() ? q->second : options.parameter_psd;
  }
  problem.prior = prior_std.cwiseAbs2().asDiagonal();
  result.prior_covariance = problem.prior;
  const int nx = vehicle.model.NumStates();
  problem.qx.resize(nx);
  for (int i = 0; i < nx; ++i) {
    problem.qx[i] = i < kNumStates ? options.state_psd[i] : options.effect_state_psd;
  }
  const long adaptation_rows = options.noise_adaptation_rows > 0
                                  ? std::min(rows_per_pass, options.noise_adaptation_rows)
                                  : rows_per_pass;
  problem.total_rows = rows_per_pass * (covariance_pass ? 2 : 1) +
                       adaptation_rows * options.noise_adaptations;
  if (options.smoother) {
    problem.total_rows += SmootherRecomputedRows(rows_per_pass, options.smoother_block_rows);
  }

  // Histories: in result.logs unless the caller takes them.
  std::unique_ptr<EkfMemoryHistory> in_memory;
  if (history == nullptr) {
    in_memory = std::make_unique<EkfMemoryHistory>(logs, vehicle.model.StateNames(), np,
                                                   options.smoother, covariance_pass,
                                                   &result.logs);
    history = in_memory.get();
  }

  long rows_done = 0;
  auto failed = [&](const PassResult& pass) {
    result.usable = false;
    result.failure = pass.failure;
    result.failure_time = pass.failure_time;
    result.total_s = Seconds(start, Clock::now());
    return result;
  };
  auto add_effort = [&](const PassResult& pass) {
    result.propagation_s += pass.propagation_s;
    result.update_s += pass.update_s;
    result.smoother_s += pass.smoother_s;
    result.updates += pass.updates;
    result.propagation += pass.counters;
    result.integrator += pass.integrator;
  };

  // Pass 1: estimation; with noise adaptation, first the passes that
  // re-estimate R from their innovations.
  result.noise_initial = noise;
  EkfPassRecord record1;
  record1.parameters = true;
  record1.innovations = true;
  for (int a = 0; a < options.noise_adaptations; ++a) {
    const PassResult pass = RunPass(problem, p0, false, false, record1, history, &rows_done,
                                    adaptation_rows);
    if (!pass.ok) return failed(pass);
    add_effort(pass);
    // Mehra (1970): E[nu nu^T] = H P H^T + R, so R_ii = mean(nu_i^2 - (H P H^T)_ii)
    // = R_ii + mean(nu_i^2 - S_ii) over the updates after the burn-in.
    for (const auto& [name, acc] : pass.channel_stats) {
      if (acc.count < 10) continue;
      const double r_old = problem.noise.std.at(name) * problem.noise.std.at(name);
      const double r_new = r_old + (acc.innovation_squares - acc.innovation_variance) / acc.count;
      problem.noise.std[name] = std::sqrt(std::max(r_new, 1e-4 * r_old));
    }
  }
  result.noise = problem.noise;
  record1.states = !covariance_pass;
  const Clock::time_point c1 = Clock::now();
  const PassResult pass1 = RunPass(problem, p0, false, options.smoother && !covariance_pass,
                                   record1, history, &rows_done);
  result.estimation_pass_s = Seconds(c1, Clock::now());
  if (!pass1.ok) return failed(pass1);
  add_effort(pass1);
  const Eigen::VectorXd p_final = pass1.z.tail(np);
  result.estimate = p_final.cwiseProduct(free.scales());
  result.filter_std =
      pass1.P.diagonal().tail(np).cwiseMax(0.0).cwiseSqrt().cwiseProduct(free.scales());
  for (int k = 0; k < np; ++k) result.parameters.SetValue(free.names()[k], result.estimate[k]);
  Eigen::MatrixXd covariance = pass1.P.bottomRightCorner(np, np);

  long total_rows = problem.total_rows;  // for progress; grows with each refinement's pass
  // Pass 2: covariance at the estimate (and the reported states); with the
  // refinement (header comment) first the Gauss-Newton steps it calls for.
  if (covariance_pass) {
    EkfPassRecord record2;
    record2.states = true;
    record2.std_at_estimate = true;
    auto frozen_pass = [&](const Eigen::VectorXd& p, bool final_pass) {
      Vehicle at = anchored;
      for (int k = 0; k < np; ++k) at.parameters.SetValue(free.names()[k], p[k] * free.scales()[k]);
      const EkfProblem frozen{at, logs, problem.noise, options, free,
                              problem.lower, problem.upper, problem.qp, problem.prior,
                              problem.qx, total_rows};
      const Clock::time_point c = Clock::now();
      PassResult pass = RunPass(frozen, p, true, final_pass && options.smoother,
                                final_pass ? record2 : EkfPassRecord(), history, &rows_done);
      result.covariance_pass_s += Seconds(c, Clock::now());
      if (pass.ok) add_effort(pass);
      return pass;
    };
    PassResult pass2 = frozen_pass(p_final, true);
    if (!pass2.ok) return failed(pass2);
    const Refinement refined =
        Refine(p_final, pass2, options, problem.lower, problem.upper, [&](const Eigen::VectorXd& p) {
          total_rows += rows_per_pass;
          return frozen_pass(p, false);
        });
    result.refinements = refined.steps;
    result.step_std_at_pass1 = refined.step_std_at_start;
    result.step_std_at_estimate = refined.step_std;
    result.refinement_converged = refined.converged;
    result.refinement_stop = refined.stop;
    result.frozen_log_likelihood_at_pass1 = pass2.log_likelihood;
    if (refined.steps > 0) {  // the covariance pass again, at the refined estimate
      total_rows += rows_per_pass;
      pass2 = frozen_pass(refined.p, true);
      if (!pass2.ok) return failed(pass2);
      result.estimate = refined.p.cwiseProduct(free.scales());
      for (int k = 0; k < np; ++k) result.parameters.SetValue(free.names()[k], result.estimate[k]);
    }
    result.frozen_log_likelihood = pass2.log_likelihood;
    covariance = pass2.P.bottomRightCorner(np, np);
    if (!result.refinement_converged) {
      result.short_of_maximum = LargeSteps(refined.p, pass2, options.refine_tolerance_std,
                                           problem.lower, problem.upper, free.names());
      result.notes.push_back(
          "The estimate is short of the maximum of the filter's likelihood (" +
          result.refinement_stop + " after " + std::to_string(result.refinements) +
          " Gauss-Newton refinements): a further step would move " + result.short_of_maximum +
          ". Their std describe the curvature at a point short of the maximum: judge them "
          "with output_error (or start the EKF from its estimates).");
    }
  }
  if (options.progress && rows_done % options.progress_every_rows != 0) {
    options.progress(rows_done, total_rows);
  }
  result.covariance = covariance;
  result.estimate_std = covariance.diagonal().cwiseMax(0.0).cwiseSqrt().cwiseProduct(free.scales());
  result.estimates_from =
      std::string("the filter's estimate at the end of the last log") +
      (result.refinements > 0
           ? ", refined by " + std::to_string(result.refinements) +
                 " Gauss-Newton steps of the filter's likelihood"
           : std::string(options.smoother ? " (equal to the smoothed value there)" : "")) +
      (covariance_pass
           ? "; std from a second pass linearised at that estimate (covariance pass)"
           : "; std from the filter");
  result.clamped = pass1.clamped;
  if (result.clamped > 0) {
    result.notes.push_back("The estimation pass projected parameters back onto their bounds " +
                           std::to_string(result.clamped) +
                           " times: check the final values against the config's bounds.");
  }
  result.rejected = pass1.rejected;
  if (!result.rejected.empty()) {
    std::string list;
    long all = 0;
    for (const auto& [channel, count] : result.rejected) {
      list += (list.empty() ? "" : ", ") + channel + " " + std::to_string(count);
      all += count;
    }
    result.notes.push_back("The innovation gate (a sample beyond the chi-square(1) quantile at "
                           "1 - " + NumberText(options.gate_probability, "%g") + ") rejected " +
                           std::to_string(all) + " samples as glitches: " + list + ".");
  }
  result.log_likelihood = pass1.log_likelihood;
  result.rows = rows_per_pass;

  // Identifiability.
  Eigen::VectorXd scale_scaled;
  if (result.gauge.direction.exists) {
    scale_scaled.resize(np);
    for (int k = 0; k < np; ++k) {
      scale_scaled[k] = result.gauge.direction.direction[free.indices()[k]] / free.scales()[k];
    }
  }
  // Against the uninformative start: a prior given by name (--prior, an
  // earlier report) is information, so what it fixes (the scale, by a prior
  // on d) counts as determined and its std propagates.
  const Eigen::MatrixXd uninformative =
      result.prior_covariance.diagonal()
          .cwiseMax(options.initial_parameter_std * options.initial_parameter_std)
          .asDiagonal();
  result.undetermined = FindUndeterminedDirections(
      uninformative, result.covariance, options.undetermined_variance_ratio, scale_scaled);
  result.identifiable.assign(np, true);
  for (const UndeterminedDirection& d : result.undetermined) {
    std::string loads;
    for (int k = 0; k < np; ++k) {
      // A parameter with a tenth of the direction's weight moves along it.
      if (std::fabs(d.direction[k]) > 0.1) {
        result.identifiable[k] = false;
        char buffer[64];
        std::snprintf(buffer, sizeof buffer, "%s%s %+.2f", loads.empty() ? "" : ", ",
                      free.names()[k].c_str(), d.direction[k]);
        loads += buffer;
      }
    }
    char buffer[200];
    std::snprintf(buffer, sizeof buffer,
                  "Undetermined direction (final / prior variance %.2f; |cos| to the scale "
                  "direction of model.md decision 8: %.3f), scaled coordinates: ",
                  d.variance_ratio, d.cos_to_scale);
    result.notes.push_back(buffer + loads +
                           ". These parameters are not separately identifiable from these "
                           "logs; no std is reported for them.");
  }
  result.ratios =
      ScaleFreeRatios(result.gauge, result.parameters, free.indices(),
                      free.scales().asDiagonal() * result.covariance * free.scales().asDiagonal());

  // Consistency (pass 1).
  for (const auto& [name, a] : pass1.channel_stats) {
    NisStatistic s;
    s.channel = name;
    s.dof = a.count;
    s.mean = a.count > 0 ? a.nis / a.count : kNaN;
    std::tie(s.lower, s.upper) = ChiSquareMeanBand(static_cast<double>(a.count));
    s.innovation_rms = a.count > 0 ? std::sqrt(a.innovation_squares / a.count) : kNaN;
    result.channel_nis.push_back(s);
  }
  result.total_nis.channel = "all";
  result.total_nis.dof = pass1.total_dof;
  result.total_nis.mean = pass1.total_dof > 0 ? pass1.total_nis / pass1.total_dof : kNaN;
  std::tie(result.total_nis.lower, result.total_nis.upper) =
      ChiSquareMeanBand(static_cast<double>(pass1.total_dof));
  result.total_nis.innovation_rms = kNaN;

  // Convergence: time after which each recursive estimate stays within 3 final std.
  result.settled_after_s.assign(np, 0.0);
  std::vector<double> offsets(logs.size(), 0.0);  // of each log's start in the chain
  for (size_t L = 1; L < logs.size(); ++L) {
    offsets[L] = offsets[L - 1] + logs[L - 1].inputs.times().back() - logs[L - 1].inputs.time(0);
  }
  history->VisitParameters([&](int L, int row, const EkfRowValues& p) {
    for (int k = 0; k < np; ++k) {
      if (std::fabs(p[k] - result.estimate[k]) > 3 * result.estimate_std[k]) {
        result.settled_after_s[k] = offsets[L] + logs[L].inputs.time(row) - logs[L].inputs.time(0);
      }
    }
  });

  result.total_s = Seconds(start, Clock::now());
  result.usable = true;
  return result;
}

}  // namespace coaxid
