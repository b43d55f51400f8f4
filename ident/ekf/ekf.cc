#include "ident/ekf/ekf.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>

#include <Eigen/Cholesky>
#include <glog/logging.h>

#include "core/errors.h"
#include "core/report_values.h"
#include "dynamics/outputs.h"
#include "ident/ekf/rts_smoother.h"
#include "ident/free_parameters.h"

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

struct ChannelAccumulator {
  double nis = 0, innovation_squares = 0, innovation_variance = 0;  // sums of nu^2/S, nu^2, S
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
  if (!(gate_probability >= 0 && gate_probability < 1)) {
    return fail("gate_probability must lie in [0, 1) (0: no innovation gate)");
  }
  if (!(gate_max_s > 0)) return fail("gate_max_s must be > 0");
  if (noise_adaptations < 0 || noise_adaptations > 5) {
    return fail("noise_adaptations must lie in 0 .. 5");
  }
  return true;
}


namespace {

// What every pass shares.
struct Problem {
  const Vehicle& vehicle;
  const std::vector<EstimationLog>& logs;
  NoiseWeights noise;
  const EkfOptions& options;
  const FreeParameters& free;
  Eigen::VectorXd lower, upper;  // scaled bounds
  Eigen::VectorXd qp;            // parameter random walk, scaled
  Eigen::MatrixXd prior;         // parameter prior covariance, scaled
  Eigen::Matrix<double, kNumStates, 1> qx;
  long total_rows = 0;  // over every pass, for progress
};

// What a pass records in the histories.
struct PassRecord {
  bool states = false;           // states (and smoothed ones when smoothing)
  bool parameters = false;       // the recursive parameter estimates
  bool std_at_estimate = false;  // the covariance pass's parameter std
  bool innovations = false;      // innovations, NIS statistics, log-likelihood
};

struct PassResult {
  bool ok = true;
  std::string failure;
  double failure_time = 0;
  Eigen::VectorXd z;  // final augmented state
  Eigen::MatrixXd P;  // and covariance
  std::map<std::string, ChannelAccumulator> channel_stats;
  std::map<std::string, long> rejected;  // innovation gate: samples rejected per channel
  double total_nis = 0, log_likelihood = 0;
  long total_dof = 0, clamped = 0, updates = 0;
  double propagation_s = 0, update_s = 0, smoother_s = 0;
  EkfPropagator::Counters counters;
  Integrator::Stats integrator;
};

// One pass of the filter over every log, from parameters p_start (scaled)
// with the prior covariance. freeze: keep the parameters' mean (covariance
// pass). smooth: run the RTS smoother at the end.
PassResult RunPass(const Problem& pb, const Eigen::VectorXd& p_start, bool freeze, bool smooth,
                   const PassRecord& rec, std::vector<EkfLogHistory>* histories,
                   long* rows_done) {
  const EkfOptions& options = pb.options;
  const FreeParameters& free = pb.free;
  const int np = free.size();
  const int n = kNumStates + np;
  const Eigen::VectorXd& scales = free.scales();
  PassResult out;

  Eigen::VectorXd theta = pb.vehicle.parameters.Values();
  for (int k = 0; k < np; ++k) theta[free.indices()[k]] = p_start[k] * scales[k];
  EkfPropagator propagator(pb.vehicle.model, theta, free.indices(), scales, pb.qx, pb.qp,
                           options.transition, options.integrator, options.max_substep_s);
  propagator.SetParameters(p_start.cwiseProduct(scales), scales);
  long total_rows = 0;
  for (const EstimationLog& log : pb.logs) total_rows += log.NumRows();
  RtsSmoother smoother(n);
  std::vector<std::pair<int, int>> step_rows;  // (log, row) of each smoother step
  if (smooth) {
    smoother.Reserve(static_cast<int>(total_rows));
    step_rows.reserve(total_rows);
  }

  Eigen::VectorXd z = Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(n, n);
  z.tail(np) = p_start;
  P.bottomRightCorner(np, np) = pb.prior;

  // Workspace.
  Eigen::VectorXd z_pred(n);
  Eigen::MatrixXd P_pred(n, n), Phi = Eigen::MatrixXd::Identity(n, n);
  EkfTransition transition;
  Eigen::MatrixXd H, HP, PHt, S, K, THt, T(n, n);
  Eigen::VectorXd nu, r_diag;
  Eigen::Matrix<double, kNumFlightChannels, 1> y_hat;
  Eigen::Matrix<double, kNumFlightChannels, Eigen::Dynamic> H_model;
  // A state channel's row of H is a unit vector unless a measurement effect
  // (a gyro bias) sits between the state and the log.
  const bool states_are_logged = !pb.vehicle.model.ChangesFlightMeasurements();
  auto unit_row = [&](int channel) { return channel < kNumStates && states_are_logged; };
  Eigen::LLT<Eigen::MatrixXd> llt;
  std::vector<int> present;  // columns of the log measured in this row
  // Innovation gate: a sample whose normalised innovation nu^2 / S exceeds
  // the chi-square(1) quantile at 1 - gate_probability is a glitch, dropped
  // from the update and counted; a column rejected for longer than
  // gate_max_s without a break is not glitching (a sensor fault, or a filter
  // that has lost the channel): the pass fails, naming it.
  const bool gating = options.gate_probability > 0;
  const double gate = gating ? InnovationGateThreshold(options.gate_probability) : 0;
  std::vector<double> rejected_since;
  std::deque<std::pair<double, std::pair<double, int>>> window;  // (t, (nis, dof))
  double window_nis = 0;
  long window_dof = 0;
  std::string why;

  auto fail = [&](double t, const EstimationLog& log, int row, const std::string& reason) {
    out.ok = false;
    out.failure_time = t;
    out.failure = "EKF failed at " + Time(t) + " in " + log.source + " (row " +
                  std::to_string(log.first_log_row + row + 1) + " of the log): " + reason;
    return out;
  };

  for (size_t L = 0; L < pb.logs.size(); ++L) {
    const EstimationLog& log = pb.logs[L];
    const int N = log.NumRows();
    const int m_all = log.NumChannels();
    EkfLogHistory& h = (*histories)[L];
    rejected_since.assign(m_all, kNaN);
    Eigen::VectorXd R(m_all);
    for (int c = 0; c < m_all; ++c) {
      const double s = pb.noise.std.at(log.channel_names[c]);
      R[c] = s * s;
    }
    auto record = [&](int row) {
      if (rec.states) {
        h.states.row(row) = z.head<kNumStates>().transpose();
        h.state_std.row(row) = P.diagonal().head<kNumStates>().cwiseMax(0.0).cwiseSqrt().transpose();
      }
      if (np == 0) return;
      const Eigen::VectorXd p_std = P.diagonal().tail(np).cwiseMax(0.0).cwiseSqrt().cwiseProduct(scales);
      if (rec.parameters) {
        h.parameters.row(row) = z.tail(np).cwiseProduct(scales).transpose();
        h.parameter_std.row(row) = p_std.transpose();
      }
      if (rec.std_at_estimate) h.parameter_std_at_estimate.row(row) = p_std.transpose();
    };

    // Row 0: the initial state, P0 = R for the states it holds; the
    // parameters (mean and covariance) carry over from the previous log.
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
    if (L > 0 && smooth) {
      // Log boundary: the states restart independently; the parameters carry over.
      Eigen::MatrixXd boundary = Eigen::MatrixXd::Zero(n, n);
      boundary.bottomRightCorner(np, np).setIdentity();
      const Clock::time_point c0 = Clock::now();
      if (!smoother.AddTransition(z, P, boundary, z0, P0, &why)) {
        return fail(log.inputs.time(0), log, 0, why);
      }
      out.smoother_s += Seconds(c0, Clock::now());
    }
    z = z0;
    P = P0;
    if (smooth) step_rows.push_back({static_cast<int>(L), 0});
    record(0);
    ++*rows_done;

    // The interval as applied: a lagged input (servo_lag, motor_lag) carries its lag
    // from row to row at the current estimate (dynamics/held_input.h).
    HeldInput held = HeldInput::Steady(log.inputs.input(0), log.inputs.time(0));
    for (int k = 1; k < N; ++k) {
      const double t0 = log.inputs.time(k - 1), t1 = log.inputs.time(k);
      // Predict over the hold interval [t_{k-1}, t_k) with u_{k-1}.
      const Clock::time_point c0 = Clock::now();
      if (!freeze) propagator.SetParameters(z.tail(np).cwiseProduct(scales), scales);
      const State x = z.head<kNumStates>();
      if (!propagator.Propagate(t0, t1, held, x, &transition)) {
        return fail(t0, log, k - 1,
                    "propagation to " + Time(t1) + " failed: " + propagator.last_error());
      }
      const StateMatrix& A = transition.A;
      const StateByParameter& B = transition.B;
      z_pred.head<kNumStates>() = transition.x;
      z_pred.tail(np) = z.tail(np);
      {
        // P <- Phi P Phi^T + Qd with Phi = [[A, B], [0, I]], block by block.
        const auto Pxx = P.topLeftCorner<kNumStates, kNumStates>();
        const auto Pxp = P.topRightCorner(kNumStates, np);
        const auto Ppp = P.bottomRightCorner(np, np);
        StateMatrix M = A * Pxx;
        StateByParameter Nxp = A.lazyProduct(Pxp);
        if (np > 0) {
          M.noalias() += B.lazyProduct(Pxp.transpose());
          Nxp.noalias() += B.lazyProduct(Ppp);
        }
        StateMatrix Pxx_new = M * A.transpose() + transition.Qxx;
        if (np > 0) Pxx_new.noalias() += Nxp.lazyProduct(B.transpose());
        P_pred.topLeftCorner<kNumStates, kNumStates>() = 0.5 * (Pxx_new + Pxx_new.transpose());
        P_pred.topRightCorner(kNumStates, np) = Nxp + transition.Qxp;
        P_pred.bottomLeftCorner(np, kNumStates) = P_pred.topRightCorner(kNumStates, np).transpose();
        P_pred.bottomRightCorner(np, np) = Ppp;
        P_pred.bottomRightCorner(np, np).diagonal() += (t1 - t0) * pb.qp;
      }
      const Clock::time_point c1 = Clock::now();
      out.propagation_s += Seconds(c0, c1);
      if (smooth) {
        Phi.topLeftCorner<kNumStates, kNumStates>() = A;
        Phi.topRightCorner(kNumStates, np) = B;
        if (!smoother.AddTransition(z, P, Phi, z_pred, P_pred, &why)) return fail(t1, log, k, why);
        step_rows.push_back({static_cast<int>(L), k});
      }
      z = z_pred;
      P = P_pred;
      const Clock::time_point c2 = Clock::now();
      out.smoother_s += Seconds(c1, c2);

      // Update with the channels row k holds.
      present.clear();
      bool need_model = false;
      for (int c = 0; c < m_all; ++c) {
        if (std::isfinite(log.values(k, c))) {
          present.push_back(c);
          need_model = need_model || !unit_row(log.channels[c]);
        }
      }
      auto innovation_of = [&](int c) {
        const int channel = log.channels[c];
        const double innovation = log.values(k, c) - y_hat[channel];
        return IsAngleChannel(channel) ? WrapAngle(innovation) : innovation;
      };
      held = NextHeldInput(held, pb.vehicle.model.InputLags(propagator.theta().data()),
                           log.inputs.input(k), t1);
      if (!present.empty()) {
        const State x_pred = z.head<kNumStates>();
        if (!FlightOutputsAndJacobian(pb.vehicle.model, propagator.theta(), free.indices(),
                                      scales, x_pred, held, &y_hat,
                                      need_model ? &H_model : nullptr)) {
          return fail(t1, log, k, "output model not finite (state or parameters blown up)");
        }
      }
      if (gating) {  // the gate on each sample's own S_jj = (H P H^T)_jj + R_jj
        size_t kept = 0;
        for (const int c : present) {
          const int channel = log.channels[c];
          const double hph = unit_row(channel)
                                 ? P(channel, channel)
                                 : H_model.row(channel) * P * H_model.row(channel).transpose();
          const double innovation = innovation_of(c);
          const double nis = innovation * innovation / (hph + R[c]);
          if (nis > gate) {
            if (!std::isfinite(rejected_since[c])) rejected_since[c] = t1;
            if (t1 - rejected_since[c] > options.gate_max_s) {
              char buffer[400];
              std::snprintf(buffer, sizeof buffer,
                            "channel %s: every sample since t = %.3f s rejected by the innovation "
                            "gate (now nu^2 / S = %.3g, gate %.3g): a fault or step in this "
                            "sensor, or a filter that has lost it; check the channel (or drop "
                            "it), raise the process noise if the model cannot follow it, or turn "
                            "the gate off (gate probability 0) to see the filter diverge",
                            log.channel_names[c].c_str(), rejected_since[c], nis, gate);
              return fail(t1, log, k, buffer);
            }
            if (rec.innovations) ++out.rejected[log.channel_names[c]];
            continue;
          }
          rejected_since[c] = kNaN;
          present[kept++] = c;
        }
        present.resize(kept);
      }
      const int m = static_cast<int>(present.size());
      if (m > 0) {
        H.setZero(m, n);
        nu.resize(m);
        r_diag.resize(m);
        for (int j = 0; j < m; ++j) {
          const int c = present[j];
          const int channel = log.channels[c];
          nu[j] = innovation_of(c);
          r_diag[j] = R[c];
          if (unit_row(channel)) {
            H(j, channel) = 1.0;
          } else {
            H.row(j) = H_model.row(channel);
          }
        }
        // H is sparse: a state channel's row is a unit vector. X H^T takes
        // columns of X for those, a product only for the model's rows.
        auto times_Ht = [&](const Eigen::MatrixXd& X, Eigen::MatrixXd* out) {
          out->resize(X.rows(), m);
          for (int j = 0; j < m; ++j) {
            const int channel = log.channels[present[j]];
            if (unit_row(channel)) {
              out->col(j) = X.col(channel);
            } else {
              out->col(j).noalias() = X * H.row(j).transpose();
            }
          }
        };
        times_Ht(P, &PHt);
        HP = PHt.transpose();  // m x n (P symmetric)
        times_Ht(HP, &S);
        S.diagonal() += r_diag;
        for (int j = 0; j < m; ++j) S(j, j) = std::max(S(j, j), r_diag[j]);  // floor
        llt.compute(S);
        if (llt.info() != Eigen::Success) {
          return fail(t1, log, k, "innovation covariance not positive definite");
        }
        K = llt.solve(HP).transpose();  // n x m
        const double nis = llt.matrixL().solve(nu).squaredNorm();
        if (freeze) {
          z.head<kNumStates>().noalias() += K.topRows<kNumStates>() * nu;
        } else {
          z.noalias() += K * nu;
        }
        // Joseph form, (I - K H) P (I - K H)^T + K R K^T, evaluated as
        // T - (T H^T - K R) K^T with T = (I - K H) P = P - K (H P): the same
        // matrix in O(n^2 m) instead of O(n^3).
        T = P;
        T.noalias() -= K * HP;
        times_Ht(T, &THt);
        THt.noalias() -= K * r_diag.asDiagonal();
        P = T;
        P.noalias() -= THt * K.transpose();
        P = 0.5 * (P + P.transpose()).eval();
        if (!freeze) {
          for (int j = 0; j < np; ++j) {
            double& v = z[kNumStates + j];
            if (v < pb.lower[j] || v > pb.upper[j]) {
              v = std::clamp(v, pb.lower[j], pb.upper[j]);
              ++out.clamped;
            }
          }
        }
        ++out.updates;
        if (rec.innovations) {
          out.log_likelihood -= 0.5 * (nis + 2 * llt.matrixLLT().diagonal().array().log().sum() +
                                       m * std::log(2 * M_PI));
          h.nis[k] = nis;
          h.nis_dof[k] = m;
          const bool counted = t1 - log.inputs.time(0) >= options.nis_burn_in_s;
          for (int j = 0; j < m; ++j) {
            h.innovations(k, present[j]) = nu[j];
            h.innovation_std(k, present[j]) = std::sqrt(S(j, j));
            if (counted) {
              ChannelAccumulator& a = out.channel_stats[log.channel_names[present[j]]];
              a.nis += nu[j] * nu[j] / S(j, j);
              a.innovation_squares += nu[j] * nu[j];
              a.innovation_variance += S(j, j);
              ++a.count;
            }
          }
          if (counted) {
            out.total_nis += nis;
            out.total_dof += m;
          }
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
        if (t1 - log.inputs.time(0) >= options.divergence_window_s && window_dof > 0 &&
            window_nis / window_dof > options.divergence_nis) {
          char buffer[200];
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
      out.update_s += Seconds(c2, Clock::now());
      record(k);
      ++*rows_done;
      if (options.progress && *rows_done % options.progress_every_rows == 0) {
        options.progress(*rows_done, pb.total_rows);
      }
    }
    window.clear();
    window_nis = 0;
    window_dof = 0;
  }
  {
    const Eigen::LLT<Eigen::MatrixXd> check(P);
    if (check.info() != Eigen::Success) {
      const EstimationLog& log = pb.logs.back();
      return fail(log.inputs.times().back(), log, log.NumRows() - 1,
                  "final covariance not positive definite");
    }
  }
  if (smooth) {
    const Clock::time_point c0 = Clock::now();
    CHECK_EQ(static_cast<size_t>(smoother.size() + 1), step_rows.size());
    smoother.Smooth(z, P, [&](int step, const Eigen::VectorXd& xs, const Eigen::MatrixXd& Ps) {
      const auto [L, row] = step_rows[step];
      EkfLogHistory& h = (*histories)[L];
      h.smoothed_states.row(row) = xs.head<kNumStates>().transpose();
      h.smoothed_state_std.row(row) =
          Ps.diagonal().head<kNumStates>().cwiseMax(0.0).cwiseSqrt().transpose();
    });
    out.smoother_s += Seconds(c0, Clock::now());
  }
  out.z = z;
  out.P = P;
  out.counters = propagator.counters();
  out.integrator = propagator.integrator_stats();
  return out;
}

}  // namespace

EkfResult RunEkf(const Vehicle& vehicle, const std::vector<EstimationLog>& logs,
                 const NoiseWeights& noise, const EkfOptions& options) {
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
  Problem problem{anchored, logs, noise, options, free, free.ScaledLower(), free.ScaledUpper(),
                  Eigen::VectorXd(), Eigen::MatrixXd(), Eigen::Matrix<double, kNumStates, 1>()};
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
  for (int i = 0; i < kNumStates; ++i) problem.qx[i] = options.state_psd[i];
  const int passes = (covariance_pass ? 2 : 1) + options.noise_adaptations;
  problem.total_rows = rows_per_pass * passes;

  // Histories.
  result.logs.resize(logs.size());
  for (size_t L = 0; L < logs.size(); ++L) {
    const EstimationLog& log = logs[L];
    EkfLogHistory& h = result.logs[L];
    const int N = log.NumRows(), m = log.NumChannels();
    h.source = log.source;
    h.name = log.name;
    h.times = log.inputs.times();
    h.channels = log.channels;
    h.channel_names = log.channel_names;
    h.measured = log.values;
    h.states.setConstant(N, kNumStates, kNaN);
    h.state_std.setConstant(N, kNumStates, kNaN);
    if (options.smoother) {
      h.smoothed_states.setConstant(N, kNumStates, kNaN);
      h.smoothed_state_std.setConstant(N, kNumStates, kNaN);
    }
    h.parameters.setConstant(N, np, kNaN);
    h.parameter_std.setConstant(N, np, kNaN);
    if (covariance_pass) h.parameter_std_at_estimate.setConstant(N, np, kNaN);
    h.innovations.setConstant(N, m, kNaN);
    h.innovation_std.setConstant(N, m, kNaN);
    h.nis.assign(N, kNaN);
    h.nis_dof.assign(N, 0);
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
    result.propagation.intervals += pass.counters.intervals;
    result.propagation.substeps += pass.counters.substeps;
    result.propagation.jacobians += pass.counters.jacobians;
    result.integrator.steps += pass.integrator.steps;
    result.integrator.rhs_evals += pass.integrator.rhs_evals;
    result.integrator.jac_evals += pass.integrator.jac_evals;
    result.integrator.restarts += pass.integrator.restarts;
  };

  // Pass 1: estimation; with noise adaptation, first the passes that
  // re-estimate R from their innovations.
  result.noise_initial = noise;
  PassRecord record1;
  record1.parameters = true;
  record1.innovations = true;
  for (int a = 0; a < options.noise_adaptations; ++a) {
    const PassResult pass = RunPass(problem, p0, false, false, record1, &result.logs, &rows_done);
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
                                   record1, &result.logs, &rows_done);
  result.estimation_pass_s = Seconds(c1, Clock::now());
  if (!pass1.ok) return failed(pass1);
  add_effort(pass1);
  const Eigen::VectorXd p_final = pass1.z.tail(np);
  result.estimate = p_final.cwiseProduct(free.scales());
  result.filter_std =
      pass1.P.diagonal().tail(np).cwiseMax(0.0).cwiseSqrt().cwiseProduct(free.scales());
  for (int k = 0; k < np; ++k) result.parameters.SetValue(free.names()[k], result.estimate[k]);
  Eigen::MatrixXd covariance = pass1.P.bottomRightCorner(np, np);

  // Pass 2: covariance at the estimate (and the reported states).
  if (covariance_pass) {
    PassRecord record2;
    record2.states = true;
    record2.std_at_estimate = true;
    Vehicle at_estimate = anchored;
    at_estimate.parameters = result.parameters;
    const Problem problem2{at_estimate, logs, problem.noise, options, free, problem.lower, problem.upper,
                           problem.qp, problem.prior, problem.qx, problem.total_rows};
    const Clock::time_point c2 = Clock::now();
    const PassResult pass2 =
        RunPass(problem2, p_final, true, options.smoother, record2, &result.logs, &rows_done);
    result.covariance_pass_s = Seconds(c2, Clock::now());
    if (!pass2.ok) return failed(pass2);
    add_effort(pass2);
    covariance = pass2.P.bottomRightCorner(np, np);
  }
  if (options.progress && rows_done % options.progress_every_rows != 0) {
    options.progress(rows_done, problem.total_rows);
  }
  result.covariance = covariance;
  result.estimate_std = covariance.diagonal().cwiseMax(0.0).cwiseSqrt().cwiseProduct(free.scales());
  result.estimates_from =
      std::string("the filter's estimate at the end of the last log") +
      (options.smoother ? " (equal to the smoothed value there)" : "") +
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
  double offset = 0;
  for (const EkfLogHistory& h : result.logs) {
    for (int k = 0; k < np; ++k) {
      for (size_t row = 0; row < h.times.size(); ++row) {
        if (std::fabs(h.parameters(row, k) - result.estimate[k]) > 3 * result.estimate_std[k]) {
          result.settled_after_s[k] = offset + h.times[row] - h.times[0];
        }
      }
    }
    offset += h.times.back() - h.times.front();
  }

  result.total_s = Seconds(start, Clock::now());
  result.usable = true;
  return result;
}

}  // namespace coaxid
