#include "ident/ekf.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>

#include <Eigen/Cholesky>
#include <glog/logging.h>

#include "core/errors.h"
#include "dynamics/outputs.h"
#include "ident/free_parameters.h"
#include "ident/rts_smoother.h"

namespace coaxid {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

bool IsAngleChannel(int channel) {
  return channel == kPhi || channel == kTheta || channel == kPsi;
}

// To (-pi, pi].
double WrapAngle(double a) { return a - 2 * M_PI * std::floor((a + M_PI) / (2 * M_PI)); }

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

std::string Time(double t) {
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "t = %.3f s", t);
  return buffer;
}

// Operating points for the scale-invariance check: up to 20 rows spread over
// the logs, states as measured (0 where absent), the rows' inputs.
std::vector<ModelSample> SamplePoints(const std::vector<EstimationLog>& logs) {
  std::vector<ModelSample> samples;
  for (const EstimationLog& log : logs) {
    const int count = std::max(1, 20 / static_cast<int>(logs.size()));
    for (int s = 0; s < count; ++s) {
      const int row = static_cast<int>((static_cast<long>(log.NumRows() - 1) * s) / count);
      ModelSample sample;
      sample.x.setZero();
      for (int i = 0; i < kNumStates; ++i) {
        const int col = log.ChannelColumn(i);
        if (col >= 0 && std::isfinite(log.values(row, col))) sample.x[i] = log.values(row, col);
      }
      sample.u = log.inputs.input(row);
      samples.push_back(sample);
    }
  }
  return samples;
}

// The filter's parameter coordinates p (EkfOptions::logarithmic_parameters):
// p_k = theta_k / scale_k, or p_k = log(|theta_k| / scale_k) for a parameter
// whose bounds keep one sign.
class Coordinates {
 public:
  Coordinates(const ParameterSet& set, const FreeParameters& free, bool logarithmic)
      : scale_(free.scales()) {
    const int np = free.size();
    log_.assign(np, false);
    sign_ = Eigen::VectorXd::Ones(np);
    lower_.resize(np);
    upper_.resize(np);
    for (int k = 0; k < np; ++k) {
      const Parameter& q = set[free.indices()[k]];
      if (logarithmic && q.lower >= 0 && q.value > 0) {
        log_[k] = true;
      } else if (logarithmic && q.upper <= 0 && q.value < 0) {
        log_[k] = true;
        sign_[k] = -1;
      }
      const double a = ToFilter(k, q.lower), b = ToFilter(k, q.upper);
      lower_[k] = std::min(a, b);
      upper_[k] = std::max(a, b);
    }
  }
  bool logarithmic(int k) const { return log_[k]; }
  double ToFilter(int k, double theta) const {
    if (!log_[k]) return theta / scale_[k];
    const double r = sign_[k] * theta / scale_[k];
    return r > 0 ? std::log(r) : -std::numeric_limits<double>::infinity();
  }
  Eigen::VectorXd ToFilter(const Eigen::VectorXd& theta) const {
    Eigen::VectorXd p(theta.size());
    for (int k = 0; k < p.size(); ++k) p[k] = ToFilter(k, theta[k]);
    return p;
  }
  Eigen::VectorXd Theta(const Eigen::VectorXd& p) const {
    Eigen::VectorXd theta(p.size());
    for (int k = 0; k < p.size(); ++k) {
      theta[k] = log_[k] ? sign_[k] * scale_[k] * std::exp(p[k]) : scale_[k] * p[k];
    }
    return theta;
  }
  // d theta / d p.
  Eigen::VectorXd Jacobian(const Eigen::VectorXd& p) const {
    Eigen::VectorXd j(p.size());
    for (int k = 0; k < p.size(); ++k) {
      j[k] = log_[k] ? sign_[k] * scale_[k] * std::exp(p[k]) : scale_[k];
    }
    return j;
  }
  const Eigen::VectorXd& lower() const { return lower_; }
  const Eigen::VectorXd& upper() const { return upper_; }

 private:
  Eigen::VectorXd scale_, sign_, lower_, upper_;
  std::vector<bool> log_;
};

struct ChannelAccumulator {
  double nis = 0, innovation_squares = 0;
  long count = 0;
};

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
                   initial_rate_std}) {
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
  if (progress_every_rows < 1) return fail("progress_every_rows must be >= 1");
  return true;
}

EkfResult RunEkf(const Vehicle& vehicle, const std::vector<EstimationLog>& logs,
                 const NoiseWeights& noise, const EkfOptions& options) {
  const Clock::time_point start = Clock::now();
  std::string why;
  if (!options.IsValid(&why)) throw InputError("EKF options: " + why);
  if (logs.empty()) throw InputError("EKF: no log to estimate from");
  long total_rows = 0;
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
    total_rows += log.NumRows();
  }
  for (const auto* by_name : {&options.parameter_psd_by_name,
                              &options.initial_parameter_std_by_name}) {
    for (const auto& entry : *by_name) {
      if (!vehicle.parameters.Has(entry.first)) {
        throw InputError("EKF options name an unknown parameter '" + entry.first + "'");
      }
    }
  }

  EkfResult result;
  result.parameters = vehicle.parameters;

  // Scale (model.md, decision 8).
  result.scale = FindScaleDirection(vehicle.model, result.parameters, SamplePoints(logs));
  if (result.scale.exists) {
    std::vector<std::string> names, fixed;
    for (int i : result.scale.group) {
      names.push_back(result.parameters[i].name);
      if (!result.parameters[i].estimated) fixed.push_back(result.parameters[i].name);
    }
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    const std::string group_note = "Flight logs determine only ratios of " + list +
                                   " (scaling them together leaves every flight output "
                                   "unchanged; model.md decision 8).";
    if (fixed.empty() && options.scale_anchor == EkfOptions::ScaleAnchor::kHubDistance) {
      result.parameters.SetEstimated(BaseParameterName(kHubDistance), false);
      result.anchored = BaseParameterName(kHubDistance);
      char buffer[96];
      std::snprintf(buffer, sizeof buffer, "%g m", result.parameters[kHubDistance].value);
      result.notes.push_back(
          group_note + " d is held fixed at its config value (" + buffer +
          ") to fix the scale; the other members are estimates relative to that d: multiply "
          "them by d_true / d_config if d is measured differently, or use the ratios reported. "
          "A balance log fixes the scale (linear_kf / output_error).");
    } else if (fixed.empty()) {
      result.notes.push_back(group_note + " All of them were augmented (no anchor): the "
                             "filter reports the undetermined direction and no std for the "
                             "parameters along it.");
    } else {
      std::string held;
      for (const std::string& n : fixed) held += (held.empty() ? "" : ", ") + n;
      result.notes.push_back(group_note + " The scale is fixed by " + held +
                             " (estimated: false in the config).");
    }
  }

  const FreeParameters free(result.parameters);
  const int np = free.size();
  const int n = kNumStates + np;
  result.free_names = free.names();
  result.free_indices = free.indices();
  result.scales = free.scales();
  const Coordinates coordinates(result.parameters, free, options.logarithmic_parameters);
  const Eigen::VectorXd& lower = coordinates.lower();
  const Eigen::VectorXd& upper = coordinates.upper();
  Eigen::VectorXd free_values(np);
  for (int k = 0; k < np; ++k) free_values[k] = result.parameters[free.indices()[k]].value;
  const Eigen::VectorXd p0 = coordinates.ToFilter(free_values);
  // d p / d (theta / scale) at the start: converts scaled-unit options.
  const Eigen::VectorXd to_filter =
      free.scales().cwiseQuotient(coordinates.Jacobian(p0)).cwiseAbs();

  // Prior and random walk of the parameters, in the filter's coordinates.
  Eigen::VectorXd prior_std(np), qp(np);
  for (int k = 0; k < np; ++k) {
    const std::string& name = free.names()[k];
    auto s = options.initial_parameter_std_by_name.find(name);
    prior_std[k] = (s != options.initial_parameter_std_by_name.end()
                        ? s->second / free.scales()[k]
                        : options.initial_parameter_std) *
                   to_filter[k];
    auto q = options.parameter_psd_by_name.find(name);
    qp[k] = (q != options.parameter_psd_by_name.end() ? q->second : options.parameter_psd) *
            to_filter[k] * to_filter[k];
  }
  const Eigen::MatrixXd prior_filter = prior_std.cwiseAbs2().asDiagonal();
  // Scaled coordinates for the result: C_scaled = D C_filter D, D = diag(dtheta/dp / scale).
  auto to_scaled = [&](const Eigen::VectorXd& p, const Eigen::MatrixXd& C) -> Eigen::MatrixXd {
    const Eigen::VectorXd D = coordinates.Jacobian(p).cwiseQuotient(free.scales());
    return D.asDiagonal() * C * D.asDiagonal();
  };
  result.prior_covariance = to_scaled(p0, prior_filter);
  Eigen::Matrix<double, kNumStates, 1> qx;
  for (int i = 0; i < kNumStates; ++i) qx[i] = options.state_psd[i];

  EkfPropagator propagator(vehicle.model, result.parameters.Values(), free.indices(),
                           coordinates.Jacobian(p0), qx, qp, options.transition, options.integrator,
                           options.max_substep_s);
  RtsSmoother smoother(n);
  if (options.smoother) smoother.Reserve(static_cast<int>(total_rows));
  std::vector<std::pair<int, int>> step_rows;  // (log, row) of each smoother step
  step_rows.reserve(total_rows);

  Eigen::VectorXd z = Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(n, n);
  z.tail(np) = p0;
  P.bottomRightCorner(np, np) = prior_filter;
  Eigen::VectorXd dtheta_dp = coordinates.Jacobian(p0);
  for (int k = 0; k < np; ++k) {
    if (!(z[kNumStates + k] >= lower[k] && z[kNumStates + k] <= upper[k])) {
      throw InputError("initial value of " + free.names()[k] + " lies outside its bounds");
    }
  }

  // Workspace.
  Eigen::VectorXd z_pred(n);
  Eigen::MatrixXd P_pred(n, n), Phi = Eigen::MatrixXd::Identity(n, n);
  EkfTransition transition;
  Eigen::MatrixXd H, HP, S, K, IKH(n, n), T(n, n);
  Eigen::VectorXd nu, r_diag;
  Eigen::Matrix<double, kNumFlightChannels, 1> y_hat;
  Eigen::Matrix<double, 3, Eigen::Dynamic> H_acc;
  Eigen::LLT<Eigen::MatrixXd> llt;
  std::vector<int> present;  // columns of the log measured in this row

  result.logs.resize(logs.size());
  std::map<std::string, ChannelAccumulator> channel_stats;
  double total_nis = 0;
  long total_dof = 0;
  std::deque<std::pair<double, std::pair<double, int>>> window;  // (t, (nis, dof))
  double window_nis = 0;
  long window_dof = 0;
  long rows_done = 0;
  double propagation_s = 0, update_s = 0;

  auto fail = [&](double t, const EstimationLog& log, int row, const std::string& reason) {
    result.usable = false;
    result.failure_time = t;
    result.failure = "EKF failed at " + Time(t) + " in " + log.source + " (row " +
                     std::to_string(log.first_log_row + row + 1) + " of the log): " + reason;
    result.total_s = Seconds(start, Clock::now());
    return result;
  };

  for (size_t L = 0; L < logs.size(); ++L) {
    const EstimationLog& log = logs[L];
    const int N = log.NumRows();
    const int m_all = log.NumChannels();
    EkfLogHistory& h = result.logs[L];
    h.source = log.source;
    h.name = log.name;
    h.times = log.inputs.times();
    h.channels = log.channels;
    h.channel_names = log.channel_names;
    h.measured = log.values;
    h.filtered_states.setConstant(N, kNumStates, kNaN);
    h.filtered_state_std.setConstant(N, kNumStates, kNaN);
    h.parameters.setConstant(N, np, kNaN);
    h.parameter_std.setConstant(N, np, kNaN);
    h.innovations.setConstant(N, m_all, kNaN);
    h.innovation_std.setConstant(N, m_all, kNaN);
    h.nis.assign(N, kNaN);
    h.nis_dof.assign(N, 0);
    Eigen::VectorXd R(m_all);
    for (int c = 0; c < m_all; ++c) {
      const double s = noise.std.at(log.channel_names[c]);
      R[c] = s * s;
    }
    auto record = [&](int row) {
      h.filtered_states.row(row) = z.head<kNumStates>().transpose();
      h.filtered_state_std.row(row) =
          P.diagonal().head<kNumStates>().cwiseMax(0.0).cwiseSqrt().transpose();
      if (np > 0) {
        h.parameters.row(row) = coordinates.Theta(z.tail(np)).transpose();
        h.parameter_std.row(row) = P.diagonal()
                                       .tail(np)
                                       .cwiseMax(0.0)
                                       .cwiseSqrt()
                                       .cwiseProduct(coordinates.Jacobian(z.tail(np)).cwiseAbs())
                                       .transpose();
      }
    };

    // Row 0: the initial state, P0 = R for the states it holds.
    Eigen::VectorXd z0(n);
    Eigen::MatrixXd P0 = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < kNumStates; ++i) {
      const int col = log.ChannelColumn(i);
      if (col >= 0 && std::isfinite(log.values(0, col))) {
        z0[i] = log.values(0, col);
        P0(i, i) = R[col];
      } else {
        z0[i] = 0;
        const double s = i <= kZ ? options.initial_position_std
                         : i <= kW ? options.initial_velocity_std
                         : i <= kPsi ? options.initial_angle_std
                                     : options.initial_rate_std;
        P0(i, i) = s * s;
      }
    }
    z0.tail(np) = z.tail(np);
    P0.bottomRightCorner(np, np) = P.bottomRightCorner(np, np);
    if (L > 0 && options.smoother) {
      // Log boundary: the states restart independently; the parameters carry over.
      Eigen::MatrixXd boundary = Eigen::MatrixXd::Zero(n, n);
      boundary.bottomRightCorner(np, np).setIdentity();
      if (!smoother.AddTransition(z, P, boundary, z0, P0, &why)) return fail(h.times[0], log, 0, why);
    }
    z = z0;
    P = P0;
    step_rows.push_back({static_cast<int>(L), 0});
    record(0);
    ++rows_done;

    for (int k = 1; k < N; ++k) {
      const double t0 = h.times[k - 1], t1 = h.times[k];
      // Predict over the hold interval [t_{k-1}, t_k) with u_{k-1}.
      Clock::time_point c0 = Clock::now();
      dtheta_dp = coordinates.Jacobian(z.tail(np));
      propagator.SetParameters(coordinates.Theta(z.tail(np)), dtheta_dp);
      const State x = z.head<kNumStates>();
      if (!propagator.Propagate(t0, t1, log.inputs.input(k - 1), x, &transition)) {
        return fail(t0, log, k - 1,
                    "propagation to " + Time(t1) + " failed: " + propagator.last_error());
      }
      const StateMatrix& A = transition.A;
      const StateByParameter& B = transition.B;
      z_pred.head<kNumStates>() = transition.x;
      z_pred.tail(np) = z.tail(np);
      {
        const auto Pxx = P.topLeftCorner<kNumStates, kNumStates>();
        const auto Pxp = P.topRightCorner(kNumStates, np);
        const auto Ppp = P.bottomRightCorner(np, np);
        StateMatrix M = A * Pxx;
        StateByParameter Nxp = A * Pxp;
        if (np > 0) {
          M.noalias() += B * Pxp.transpose();
          Nxp.noalias() += B * Ppp;
        }
        StateMatrix Pxx_new = M * A.transpose() + transition.Qxx;
        if (np > 0) Pxx_new.noalias() += Nxp * B.transpose();
        P_pred.topLeftCorner<kNumStates, kNumStates>() = 0.5 * (Pxx_new + Pxx_new.transpose());
        P_pred.topRightCorner(kNumStates, np) = Nxp + transition.Qxp;
        P_pred.bottomLeftCorner(np, kNumStates) = P_pred.topRightCorner(kNumStates, np).transpose();
        P_pred.bottomRightCorner(np, np) = Ppp;
        P_pred.bottomRightCorner(np, np).diagonal() += (t1 - t0) * qp;
      }
      if (options.smoother) {
        Phi.topLeftCorner<kNumStates, kNumStates>() = A;
        Phi.topRightCorner(kNumStates, np) = B;
        if (!smoother.AddTransition(z, P, Phi, z_pred, P_pred, &why)) return fail(t1, log, k, why);
      }
      z = z_pred;
      P = P_pred;
      step_rows.push_back({static_cast<int>(L), k});
      Clock::time_point c1 = Clock::now();
      propagation_s += Seconds(c0, c1);

      // Update with the channels row k holds.
      present.clear();
      bool need_acc = false;
      for (int c = 0; c < m_all; ++c) {
        if (std::isfinite(log.values(k, c))) {
          present.push_back(c);
          need_acc = need_acc || log.channels[c] >= kNumStates;
        }
      }
      const int m = static_cast<int>(present.size());
      if (m > 0) {
        const State x_pred = z.head<kNumStates>();
        if (!FlightOutputsAndJacobian(vehicle.model, propagator.theta(), free.indices(),
                                      dtheta_dp, x_pred, log.inputs.input(k), &y_hat,
                                      need_acc ? &H_acc : nullptr)) {
          return fail(t1, log, k, "output model not finite (state or parameters blown up)");
        }
        H.setZero(m, n);
        nu.resize(m);
        r_diag.resize(m);
        for (int j = 0; j < m; ++j) {
          const int c = present[j];
          const int channel = log.channels[c];
          double innovation = log.values(k, c) - y_hat[channel];
          if (IsAngleChannel(channel)) innovation = WrapAngle(innovation);
          nu[j] = innovation;
          r_diag[j] = R[c];
          if (channel < kNumStates) {
            H(j, channel) = 1.0;
          } else {
            H.row(j) = H_acc.row(channel - kAx);
          }
        }
        HP.noalias() = H * P;  // m x n; P H^T = HP^T (P symmetric)
        S.noalias() = HP * H.transpose();
        S.diagonal() += r_diag;
        for (int j = 0; j < m; ++j) S(j, j) = std::max(S(j, j), r_diag[j]);  // floor
        llt.compute(S);
        if (llt.info() != Eigen::Success) {
          return fail(t1, log, k, "innovation covariance not positive definite");
        }
        K = llt.solve(HP).transpose();  // n x m
        const double nis = llt.matrixL().solve(nu).squaredNorm();
        result.log_likelihood -=
            0.5 * (nis + 2 * llt.matrixLLT().diagonal().array().log().sum() + m * std::log(2 * M_PI));
        if (options.freeze_parameter_mean) {
          z.head<kNumStates>().noalias() += K.topRows<kNumStates>() * nu;
        } else {
          z.noalias() += K * nu;
        }
        // Joseph form.
        IKH.setIdentity();
        IKH.noalias() -= K * H;
        T.noalias() = IKH * P;
        P.noalias() = T * IKH.transpose();
        P.noalias() += K * r_diag.asDiagonal() * K.transpose();
        P = 0.5 * (P + P.transpose()).eval();
        for (int j = 0; j < np; ++j) {
          double& v = z[kNumStates + j];
          if (v < lower[j] || v > upper[j]) {
            v = std::clamp(v, lower[j], upper[j]);
            ++result.clamped;
          }
        }
        ++result.updates;
        h.nis[k] = nis;
        h.nis_dof[k] = m;
        const bool counted = t1 - h.times[0] >= options.nis_burn_in_s;
        for (int j = 0; j < m; ++j) {
          h.innovations(k, present[j]) = nu[j];
          h.innovation_std(k, present[j]) = std::sqrt(S(j, j));
          if (counted) {
            ChannelAccumulator& a = channel_stats[log.channel_names[present[j]]];
            a.nis += nu[j] * nu[j] / S(j, j);
            a.innovation_squares += nu[j] * nu[j];
            ++a.count;
          }
        }
        if (counted) {
          total_nis += nis;
          total_dof += m;
        }
        // Divergence watch.
        window.push_back({t1, {nis, m}});
        window_nis += nis;
        window_dof += m;
        while (!window.empty() && window.front().first <= t1 - options.divergence_window_s) {
          window_nis -= window.front().second.first;
          window_dof -= window.front().second.second;
          window.pop_front();
        }
        if (t1 - h.times[0] >= options.divergence_window_s && window_dof > 0 &&
            window_nis / window_dof > options.divergence_nis) {
          char buffer[160];
          std::snprintf(buffer, sizeof buffer,
                        "diverged: mean normalised innovation squared %.3g per degree of "
                        "freedom over the last %.3g s (expected 1, limit %.3g)",
                        window_nis / window_dof, options.divergence_window_s,
                        options.divergence_nis);
          return fail(t1, log, k, buffer);
        }
      }
      if (!z.allFinite() || !P.allFinite() || (P.diagonal().array() <= 0).any()) {
        return fail(t1, log, k, "state or covariance not finite or not positive");
      }
      update_s += Seconds(c1, Clock::now());
      record(k);
      ++rows_done;
      if (options.progress && rows_done % options.progress_every_rows == 0) {
        options.progress(rows_done, total_rows);
      }
    }
    window.clear();
    window_nis = 0;
    window_dof = 0;
  }
  if (options.progress && rows_done % options.progress_every_rows != 0) {
    options.progress(rows_done, total_rows);
  }
  {
    const Eigen::LLT<Eigen::MatrixXd> check(P);
    if (check.info() != Eigen::Success) {
      const EstimationLog& log = logs.back();
      return fail(log.inputs.times().back(), log, log.NumRows() - 1,
                  "final covariance not positive definite");
    }
  }

  // Final estimates: the filtered values at the end (= smoothed there).
  const Eigen::VectorXd p_final = z.tail(np);
  const Eigen::MatrixXd covariance_filter = P.bottomRightCorner(np, np);
  result.covariance = to_scaled(p_final, covariance_filter);
  result.estimate = coordinates.Theta(p_final);
  result.estimate_std = result.covariance.diagonal().cwiseSqrt().cwiseProduct(free.scales());
  for (int k = 0; k < np; ++k) result.parameters.SetValue(free.names()[k], result.estimate[k]);
  result.estimates_from = std::string("filtered at the end of the last log") +
                          (options.smoother ? " (equal to the smoothed value there)" : "");

  // Smoother.
  if (options.smoother) {
    const Clock::time_point c0 = Clock::now();
    for (EkfLogHistory& h : result.logs) {
      const int N = static_cast<int>(h.times.size());
      h.smoothed_states.setConstant(N, kNumStates, kNaN);
      h.smoothed_state_std.setConstant(N, kNumStates, kNaN);
      h.smoothed_parameters.setConstant(N, np, kNaN);
      h.smoothed_parameter_std.setConstant(N, np, kNaN);
    }
    CHECK_EQ(static_cast<size_t>(smoother.size() + 1), step_rows.size());
    smoother.Smooth(z, P, [&](int step, const Eigen::VectorXd& xs, const Eigen::MatrixXd& Ps) {
      const auto [L, row] = step_rows[step];
      EkfLogHistory& h = result.logs[L];
      h.smoothed_states.row(row) = xs.head<kNumStates>().transpose();
      h.smoothed_state_std.row(row) =
          Ps.diagonal().head<kNumStates>().cwiseMax(0.0).cwiseSqrt().transpose();
      if (np > 0) {
        h.smoothed_parameters.row(row) = coordinates.Theta(xs.tail(np)).transpose();
        h.smoothed_parameter_std.row(row) = Ps.diagonal()
                                                .tail(np)
                                                .cwiseMax(0.0)
                                                .cwiseSqrt()
                                                .cwiseProduct(coordinates.Jacobian(xs.tail(np)).cwiseAbs())
                                                .transpose();
      }
    });
    result.smoother_s = Seconds(c0, Clock::now());
  }

  // Identifiability.
  // In the filter's coordinates (where the prior is diagonal); directions
  // reported in scaled coordinates.
  Eigen::VectorXd scale_filter;
  if (result.scale.exists) {
    const Eigen::VectorXd j = coordinates.Jacobian(p_final);
    scale_filter.resize(np);
    for (int k = 0; k < np; ++k) scale_filter[k] = result.scale.direction[free.indices()[k]] / j[k];
  }
  result.undetermined = FindUndeterminedDirections(
      prior_filter, covariance_filter, options.undetermined_variance_ratio, scale_filter);
  for (UndeterminedDirection& d : result.undetermined) {
    d.direction = d.direction.cwiseProduct(coordinates.Jacobian(p_final))
                      .cwiseQuotient(free.scales())
                      .normalized();
    int largest;
    d.direction.cwiseAbs().maxCoeff(&largest);
    if (d.direction[largest] < 0) d.direction = -d.direction;
  }
  result.identifiable.assign(np, true);
  for (const UndeterminedDirection& d : result.undetermined) {
    // A parameter with a tenth of the direction's weight moves along it.
    for (int k = 0; k < np; ++k) {
      if (std::fabs(d.direction[k]) > 0.1) result.identifiable[k] = false;
    }
  }
  for (const UndeterminedDirection& d : result.undetermined) {
    std::string loads;
    for (int k = 0; k < np; ++k) {
      if (std::fabs(d.direction[k]) > 0.1) {
        char buffer[64];
        std::snprintf(buffer, sizeof buffer, "%s%s %+.2f", loads.empty() ? "" : ", ",
                      free.names()[k].c_str(), d.direction[k]);
        loads += buffer;
      }
    }
    char buffer[160];
    std::snprintf(buffer, sizeof buffer,
                  "Undetermined direction (final/prior variance %.2f; |cos| to the scale "
                  "direction %.3f): ",
                  d.variance_ratio, d.cos_to_scale);
    result.notes.push_back(buffer + loads +
                           ". The parameters along it are not separately identifiable from "
                           "these logs; no std is reported for them.");
  }
  result.ratios = ScaleRatios(result.scale, result.parameters, free.indices(), free.scales(),
                              result.covariance);

  // Consistency.
  for (const auto& [name, a] : channel_stats) {
    NisStatistic s;
    s.channel = name;
    s.dof = a.count;
    s.mean = a.count > 0 ? a.nis / a.count : kNaN;
    std::tie(s.lower, s.upper) = ChiSquareMeanBand(static_cast<double>(a.count));
    s.innovation_rms = a.count > 0 ? std::sqrt(a.innovation_squares / a.count) : kNaN;
    result.channel_nis.push_back(s);
  }
  result.total_nis.channel = "all";
  result.total_nis.dof = total_dof;
  result.total_nis.mean = total_dof > 0 ? total_nis / total_dof : kNaN;
  std::tie(result.total_nis.lower, result.total_nis.upper) =
      ChiSquareMeanBand(static_cast<double>(total_dof));
  result.total_nis.innovation_rms = kNaN;

  // Convergence: time after which each filtered parameter stays within 3 final std.
  result.settled_after_s.assign(np, 0.0);
  {
    double offset = 0;
    std::vector<double> settled(np, 0.0);
    for (const EkfLogHistory& h : result.logs) {
      for (int k = 0; k < np; ++k) {
        for (size_t row = 0; row < h.times.size(); ++row) {
          if (std::fabs(h.parameters(row, k) - result.estimate[k]) > 3 * result.estimate_std[k]) {
            settled[k] = offset + h.times[row] - h.times[0];
          }
        }
      }
      offset += h.times.back() - h.times.front();
    }
    result.settled_after_s = settled;
  }

  result.rows = rows_done;
  result.propagation_s = propagation_s;
  result.update_s = update_s;
  result.propagation = propagator.counters();
  result.integrator = propagator.integrator_stats();
  result.total_s = Seconds(start, Clock::now());
  result.usable = true;
  return result;
}

}  // namespace coaxid
