#include "ident/ekf/filter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "dynamics/outputs.h"

namespace coaxid {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// To (-pi, pi].
double WrapAngle(double a) { return a - 2 * M_PI * std::floor((a + M_PI) / (2 * M_PI)); }

std::string Time(double t) {
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "t = %.3f s", t);
  return buffer;
}

Eigen::VectorXd PropagatorTheta(const EkfProblem& pb, const Eigen::VectorXd& p_start) {
  Eigen::VectorXd theta = pb.vehicle.parameters.Values();
  for (int k = 0; k < pb.free.size(); ++k) {
    theta[pb.free.indices()[k]] = p_start[k] * pb.free.scales()[k];
  }
  return theta;
}

// P <- Phi P Phi^T + Qd with Phi = [[A, B], [0, I]], block by block, over
// an interval dt (qp: the parameters' random walk). N as in TransitionBlocks
// (fixed-size arithmetic for the 12 states).
template <int N>
void PredictCovariance(const EkfTransition& t, const Eigen::MatrixXd& P, int nx, int np,
                       double dt, const Eigen::VectorXd& qp, Eigen::MatrixXd* P_pred) {
  using Blocks = TransitionBlocks<N>;
  const typename Blocks::Square A = t.A;
  const typename Blocks::ByParameter B = t.B;
  const Eigen::Block<const Eigen::MatrixXd, N, N> Pxx(P, 0, 0, nx, nx);
  const Eigen::Block<const Eigen::MatrixXd, N, Eigen::Dynamic> Pxp(P, 0, nx, nx, np);
  const auto Ppp = P.bottomRightCorner(np, np);
  typename Blocks::Square M = A * Pxx;
  typename Blocks::ByParameter Nxp = A.lazyProduct(Pxp);
  if (np > 0) {
    M.noalias() += B.lazyProduct(Pxp.transpose());
    Nxp.noalias() += B.lazyProduct(Ppp);
  }
  typename Blocks::Square Pxx_new = M * A.transpose() + t.Qxx;
  if (np > 0) Pxx_new.noalias() += Nxp.lazyProduct(B.transpose());
  Eigen::Block<Eigen::MatrixXd, N, N>(*P_pred, 0, 0, nx, nx) =
      0.5 * (Pxx_new + Pxx_new.transpose());
  P_pred->topRightCorner(nx, np) = Nxp + t.Qxp;
  P_pred->bottomLeftCorner(np, nx) = P_pred->topRightCorner(nx, np).transpose();
  P_pred->bottomRightCorner(np, np) = Ppp;
  P_pred->bottomRightCorner(np, np).diagonal() += dt * qp;
}

}  // namespace

EkfFilter::EkfFilter(const EkfProblem& problem, const Eigen::VectorXd& p_start, bool freeze)
    : pb_(problem),
      freeze_(freeze),
      nx_(problem.vehicle.model.NumStates()),
      np_(problem.free.size()),
      n_(nx_ + problem.free.size()),
      propagator_(problem.vehicle.model, PropagatorTheta(problem, p_start), problem.free.indices(),
                  problem.free.scales(), problem.qx, problem.qp, problem.options.transition,
                  problem.options.integrator, problem.options.max_substep_s),
      // A state channel's row of H is a unit vector unless a measurement effect
      // (a gyro bias) sits between the state and the log.
      states_are_logged_(!problem.vehicle.model.ChangesFlightMeasurements()),
      // Innovation gate: a sample whose normalised innovation nu^2 / S exceeds
      // the chi-square(1) quantile at 1 - gate_probability is a glitch, dropped
      // from the update and counted; a column rejected for longer than
      // gate_max_s without a break is not glitching (a sensor fault, or a filter
      // that has lost the channel): the pass fails, naming it.
      gating_(problem.options.gate_probability > 0),
      gate_(gating_ ? InnovationGateThreshold(problem.options.gate_probability) : 0) {
  propagator_.SetParameters(p_start.cwiseProduct(pb_.free.scales()), pb_.free.scales());
  s_.log = -1;
  s_.z = Eigen::VectorXd::Zero(n_);
  s_.P = Eigen::MatrixXd::Zero(n_, n_);
  s_.z.tail(np_) = p_start;
  s_.P.bottomRightCorner(np_, np_) = pb_.prior;
  if (freeze_) s_.step = Eigen::VectorXd::Zero(n_);
  z_pred_.resize(n_);
  P_pred_.resize(n_, n_);
  phi_ = Eigen::MatrixXd::Identity(n_, n_);
  // Log boundary: the states restart independently; the parameters carry over.
  boundary_ = Eigen::MatrixXd::Zero(n_, n_);
  boundary_.bottomRightCorner(np_, np_).setIdentity();
  T_.resize(n_, n_);
}

bool EkfFilter::Fail(double t, int log, int row, const std::string& reason) {
  const EstimationLog& l = pb_.logs[log];
  failure_time_ = t;
  failure_ = "EKF failed at " + Time(t) + " in " + l.source + " (row " +
             std::to_string(l.LogRow(row) + 1) + " of the log): " + reason;
  return false;
}

void EkfFilter::Restore(const EkfFilterState& state) {
  s_ = state;
  propagator_.RestoreStepHint(state.step_hint);
  const EstimationLog& log = pb_.logs[s_.log];
  R_.resize(log.NumChannels());
  for (int c = 0; c < log.NumChannels(); ++c) {
    const double s = pb_.noise.std.at(log.channel_names[c]);
    R_[c] = s * s;
  }
}

bool EkfFilter::Predict(int L, int k) {
  const EkfOptions& options = pb_.options;
  const EstimationLog& log = pb_.logs[L];
  row_ = k;
  if (k == 0) {
    // Row 0: the initial state, P0 = R for the states it holds; the
    // parameters (mean and covariance) carry over from the previous log.
    const int m_all = log.NumChannels();
    R_.resize(m_all);
    for (int c = 0; c < m_all; ++c) {
      const double s = pb_.noise.std.at(log.channel_names[c]);
      R_[c] = s * s;
    }
    P_pred_.setZero();
    for (int i = 0; i < nx_; ++i) {
      if (i >= kNumStates) {  // an effect's own state: not logged, starts at rest
        z_pred_[i] = 0;
        P_pred_(i, i) = options.initial_effect_state_std * options.initial_effect_state_std;
        continue;
      }
      const int col = log.ChannelColumn(i);
      if (col >= 0 && std::isfinite(log.values(0, col))) {
        z_pred_[i] = log.values(0, col);
        P_pred_(i, i) = R_[col];
      } else {
        z_pred_[i] = 0;
        const double s = i <= kZ     ? options.initial_position_std
                         : i <= kW   ? options.initial_velocity_std
                         : i <= kPsi ? options.initial_angle_std
                                     : options.initial_rate_std;
        P_pred_(i, i) = s * s;
      }
    }
    z_pred_.tail(np_) = s_.z.tail(np_);
    P_pred_.bottomRightCorner(np_, np_) = s_.P.bottomRightCorner(np_, np_);
    s_.rejected_since.assign(m_all, kNaN);
    s_.window.clear();
    s_.window_nis = 0;
    s_.window_dof = 0;
    // The interval as applied: a lagged input (servo_lag, motor_lag) carries its lag
    // from row to row at the current estimate (dynamics/held_input.h).
    s_.held = FirstHeldInput(log.inputs, pb_.vehicle.model.InputLags(propagator_.theta().data()));
    s_.log = L;
    if (freeze_) s_.step.head(nx_).setZero();  // the log's states do not depend on p
    return true;
  }
  const double t0 = log.inputs.time(k - 1), t1 = log.inputs.time(k);
  const Eigen::VectorXd& scales = pb_.free.scales();
  const Eigen::VectorXd& z = s_.z;
  const Eigen::MatrixXd& P = s_.P;
  // Predict over the hold interval [t_{k-1}, t_k) with u_{k-1}.
  if (!freeze_) propagator_.SetParameters(z.tail(np_).cwiseProduct(scales), scales);
  const EkfState x = z.head(nx_);
  if (!propagator_.Propagate(t0, t1, s_.held, x, &transition_)) {
    return Fail(t0, L, k - 1,
                "propagation to " + Time(t1) + " failed: " + propagator_.last_error());
  }
  z_pred_.head(nx_) = transition_.x;
  z_pred_.tail(np_) = z.tail(np_);
  if (nx_ == kNumStates) {
    PredictCovariance<kNumStates>(transition_, P, nx_, np_, t1 - t0, pb_.qp, &P_pred_);
  } else {
    PredictCovariance<Eigen::Dynamic>(transition_, P, nx_, np_, t1 - t0, pb_.qp, &P_pred_);
  }
  phi_.topLeftCorner(nx_, nx_) = transition_.A;
  phi_.topRightCorner(nx_, np_) = transition_.B;
  if (freeze_) {  // dz <- Phi dz
    step_dx_.noalias() = transition_.A * s_.step.head(nx_);
    step_dx_.noalias() += transition_.B * s_.step.tail(np_);
    s_.step.head(nx_) = step_dx_;
  }
  return true;
}

bool EkfFilter::Update(EkfTally* tally) {
  const EkfOptions& options = pb_.options;
  const int L = s_.log, k = row_;
  const EstimationLog& log = pb_.logs[L];
  const int m_all = log.NumChannels();
  const int n = n_, np = np_;
  Eigen::VectorXd& z = s_.z;
  Eigen::MatrixXd& P = s_.P;
  z.swap(z_pred_);
  P.swap(P_pred_);
  s_.row = k;
  present_.clear();
  if (k == 0) {
    s_.step_hint = propagator_.step_hint();
    return true;
  }
  const double t1 = log.inputs.time(k);
  auto unit_row = [&](int channel) { return channel < kNumStates && states_are_logged_; };

  // Update with the channels row k holds.
  present_.clear();
  bool need_model = false;
  for (int c = 0; c < m_all; ++c) {
    if (std::isfinite(log.values(k, c))) {
      present_.push_back(c);
      need_model = need_model || !unit_row(log.channels[c]);
    }
  }
  auto innovation_of = [&](int c) {
    const int channel = log.channels[c];
    const double innovation = log.values(k, c) - y_hat_[channel];
    return IsEulerAngle(channel) ? WrapAngle(innovation) : innovation;
  };
  s_.held = NextHeldInput(s_.held, pb_.vehicle.model.InputLags(propagator_.theta().data()),
                          log.inputs.input(k), t1);
  if (!present_.empty()) {
    const EkfState x_pred = z.head(nx_);
    if (!FlightOutputsAndJacobian(pb_.vehicle.model, propagator_.theta(), pb_.free.indices(),
                                  pb_.free.scales(), x_pred, s_.held, &y_hat_,
                                  need_model ? &H_model_ : nullptr)) {
      return Fail(t1, L, k, "output model not finite (state or parameters blown up)");
    }
  }
  const bool record = tally != nullptr && tally->innovations;
  if (gating_) {  // the gate on each sample's own S_jj = (H P H^T)_jj + R_jj
    size_t kept = 0;
    for (const int c : present_) {
      const int channel = log.channels[c];
      const double hph = unit_row(channel)
                             ? P(channel, channel)
                             : H_model_.row(channel) * P * H_model_.row(channel).transpose();
      const double innovation = innovation_of(c);
      const double nis = innovation * innovation / (hph + R_[c]);
      double& since = s_.rejected_since[c];
      if (nis > gate_) {
        if (!std::isfinite(since)) since = t1;
        if (t1 - since > options.gate_max_s) {
          char buffer[400];
          std::snprintf(buffer, sizeof buffer,
                        "channel %s: every sample since t = %.3f s rejected by the innovation "
                        "gate (now nu^2 / S = %.3g, gate %.3g): a fault or step in this "
                        "sensor, or a filter that has lost it; check the channel (or drop "
                        "it), raise the process noise if the model cannot follow it, or turn "
                        "the gate off (gate probability 0) to see the filter diverge",
                        log.channel_names[c].c_str(), since, nis, gate_);
          return Fail(t1, L, k, buffer);
        }
        if (record) ++tally->rejected[log.channel_names[c]];
        continue;
      }
      since = kNaN;
      present_[kept++] = c;
    }
    present_.resize(kept);
  }
  const int m = static_cast<int>(present_.size());
  if (m > 0) {
    H_.setZero(m, n);
    nu_.resize(m);
    r_diag_.resize(m);
    for (int j = 0; j < m; ++j) {
      const int c = present_[j];
      const int channel = log.channels[c];
      nu_[j] = innovation_of(c);
      r_diag_[j] = R_[c];
      if (unit_row(channel)) {
        H_(j, channel) = 1.0;
      } else {
        H_.row(j) = H_model_.row(channel);
      }
    }
    // H is sparse: a state channel's row is a unit vector. X H^T takes
    // columns of X for those, a product only for the model's rows.
    auto times_Ht = [&](const Eigen::MatrixXd& X, Eigen::MatrixXd* out) {
      out->resize(X.rows(), m);
      for (int j = 0; j < m; ++j) {
        const int channel = log.channels[present_[j]];
        if (unit_row(channel)) {
          out->col(j) = X.col(channel);
        } else {
          out->col(j).noalias() = X * H_.row(j).transpose();
        }
      }
    };
    times_Ht(P, &PHt_);
    HP_ = PHt_.transpose();  // m x n (P symmetric)
    times_Ht(HP_, &S_);
    S_.diagonal() += r_diag_;
    for (int j = 0; j < m; ++j) S_(j, j) = std::max(S_(j, j), r_diag_[j]);  // floor
    llt_.compute(S_);
    if (llt_.info() != Eigen::Success) {
      return Fail(t1, L, k, "innovation covariance not positive definite");
    }
    K_ = llt_.solve(HP_).transpose();  // n x m
    const double nis = llt_.matrixL().solve(nu_).squaredNorm();
    nis_ = nis;
    if (freeze_) {
      z.head(nx_).noalias() += K_.topRows(nx_) * nu_;
      // The free filter's innovations are this one's less H dz, and it also
      // moves p by K_p nu: dz <- (I - K H) dz + [0; K_p nu] (exact for a
      // linear model).
      step_h_.noalias() = H_ * s_.step;
      s_.step.noalias() -= K_ * step_h_;
      s_.step.tail(np).noalias() += K_.bottomRows(np) * nu_;
    } else {
      z.noalias() += K_ * nu_;
    }
    // Joseph form, (I - K H) P (I - K H)^T + K R K^T, evaluated as
    // T - (T H^T - K R) K^T with T = (I - K H) P = P - K (H P): the same
    // matrix in O(n^2 m) instead of O(n^3).
    T_ = P;
    T_.noalias() -= K_ * HP_;
    times_Ht(T_, &THt_);
    THt_.noalias() -= K_ * r_diag_.asDiagonal();
    P = T_;
    P.noalias() -= THt_ * K_.transpose();
    P = 0.5 * (P + P.transpose()).eval();
    if (!freeze_) {
      for (int j = 0; j < np; ++j) {
        double& v = z[nx_ + j];
        if (v < pb_.lower[j] || v > pb_.upper[j]) {
          v = std::clamp(v, pb_.lower[j], pb_.upper[j]);
          if (tally != nullptr) ++tally->clamped;
        }
      }
    }
    if (tally != nullptr) {
      ++tally->updates;
      tally->log_likelihood -= 0.5 * (nis + 2 * llt_.matrixLLT().diagonal().array().log().sum() +
                                      m * std::log(2 * M_PI));
    }
    if (record) {
      const bool counted = t1 - log.inputs.time(0) >= options.nis_burn_in_s;
      for (int j = 0; j < m; ++j) {
        if (counted) {
          ChannelAccumulator& a = tally->channel_stats[log.channel_names[present_[j]]];
          a.nis += nu_[j] * nu_[j] / S_(j, j);
          a.innovation_squares += nu_[j] * nu_[j];
          a.innovation_variance += S_(j, j);
          ++a.count;
        }
      }
      if (counted) {
        tally->total_nis += nis;
        tally->total_dof += m;
      }
    }
    // Divergence watch.
    auto& window = s_.window;
    window.push_back({t1, {nis, m}});
    s_.window_nis += nis;
    s_.window_dof += m;
    while (!window.empty() && window.front().first <= t1 - options.divergence_window_s) {
      s_.window_nis -= window.front().second.first;
      s_.window_dof -= window.front().second.second;
      window.pop_front();
    }
    if (t1 - log.inputs.time(0) >= options.divergence_window_s && s_.window_dof > 0 &&
        s_.window_nis / s_.window_dof > options.divergence_nis) {
      char buffer[200];
      std::snprintf(buffer, sizeof buffer,
                    "diverged: mean normalised innovation squared %.3g per degree of "
                    "freedom over the last %.3g s (expected 1, limit %.3g)",
                    s_.window_nis / s_.window_dof, options.divergence_window_s,
                    options.divergence_nis);
      return Fail(t1, L, k, buffer);
    }
  }
  if (!z.allFinite() || !P.allFinite() || (P.diagonal().array() <= 0).any()) {
    return Fail(t1, L, k, "state or covariance not finite or not positive");
  }
  s_.step_hint = propagator_.step_hint();
  return true;
}

}  // namespace coaxid
