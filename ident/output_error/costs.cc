#include "ident/output_error/costs.h"

#include <chrono>
#include <cmath>

#include <glog/logging.h>

#include "dynamics/model_jacobian.h"
#include "dynamics/outputs.h"

namespace coaxid {

FlightSegmentCost::FlightSegmentCost(const VehicleModel& model, const FreeParameters& free,
                                     const EstimationLog& log, int first, int last,
                                     bool has_next, const std::vector<double>& channel_std,
                                     double continuity_std, const IntegratorOptions& integrator,
                                     const HeldInputPath* path,
                                     std::shared_ptr<const SegmentSimulators> simulators)
    : model_(model),
      free_(free),
      log_(log),
      path_(path),
      first_(first),
      last_(last),
      n_(model.NumStates()),
      has_next_(has_next),
      continuity_weight_(1.0 / continuity_std),
      simulators_(simulators ? std::move(simulators)
                             : std::make_shared<SegmentSimulators>(model, free, integrator)) {
  CHECK(first >= 0 && first < last && last < log.NumRows());
  SetChannelStd(channel_std);
  const int end = has_next ? last - 1 : last;
  for (int k = first; k <= end; ++k) {
    bool any = false;
    for (int c = 0; c < log.NumChannels(); ++c) {
      if (std::isfinite(log.values(k, c))) {
        terms_.push_back({k, static_cast<std::int16_t>(c),
                          static_cast<std::int16_t>(log.channels[c])});
        any = true;
      }
    }
    if (any) rows_.push_back(k);
  }
  set_num_residuals(static_cast<int>(terms_.size()) + (has_next ? n_ : 0));
  mutable_parameter_block_sizes()->push_back(n_);
  mutable_parameter_block_sizes()->push_back(free.size());
  if (has_next) mutable_parameter_block_sizes()->push_back(n_);
}

SegmentSimulators::SegmentSimulators(const VehicleModel& model, const FreeParameters& free,
                                     const IntegratorOptions& integrator,
                                     SensitivityMethod method)
    : plain(model, free.Theta(free.ScaledValues().data()), integrator),
      sensitive(model, free.Theta(free.ScaledValues().data()), integrator,
                SensitivityOptions{true, true}, free.indices(), method) {}

void FlightSegmentCost::SetChannelStd(const std::vector<double>& channel_std) {
  column_weight_.resize(channel_std.size());
  for (size_t c = 0; c < channel_std.size(); ++c) column_weight_[c] = 1.0 / channel_std[c];
}

bool FlightSegmentCost::CachedRun::At(const double* start, const double* theta) const {
  return valid && Eigen::Map<const Eigen::VectorXd>(start, start_state.size()) == start_state &&
         Eigen::Map<const Eigen::VectorXd>(theta, theta_scaled.size()) == theta_scaled;
}

const Trajectory* FlightSegmentCost::Simulate(const double* start_state,
                                              const double* theta_scaled,
                                              bool sensitivities) const {
  if (!sensitivities && plain_run_.At(start_state, theta_scaled)) {
    return plain_run_.ok ? &plain_run_.trajectory : nullptr;
  }
  // A run with sensitivities is not kept: 12 x (12 + P) numbers a sample
  // would be 0.5 MB a 1 s segment, 1.7 GB for an hour of flight. Its states
  // are kept as the point's plain run; the sensitivities live in one buffer
  // per thread until that thread's next run.
  thread_local Trajectory sensitive_run;
  Trajectory& trajectory = sensitivities ? sensitive_run : plain_run_.trajectory;
  const SimulatorPool::Lease lease =
      (sensitivities ? simulators_->sensitive : simulators_->plain).Acquire();
  Simulator& simulator = *lease;
  const Eigen::VectorXd theta = free_.Theta(theta_scaled);
  simulator.SetTheta(theta);
  using Clock = std::chrono::steady_clock;
  const auto run_start = Clock::now();
  HeldInput start;
  if (path_) start = path_->At(first_, model_.InputLags(theta.data()));
  // Sensitivities asked at the point of the last run without them (a trial
  // point the trust region accepted) run along its states.
  const bool along_plain_run = sensitivities && plain_run_.At(start_state, theta_scaled) &&
                               plain_run_.ok && plain_run_.integrated;
  const bool ok = simulator.Run(log_.inputs, first_, last_,
                                Eigen::Map<const Eigen::VectorXd>(start_state, n_),
                                &trajectory, path_ ? &start : nullptr,
                                along_plain_run ? &plain_run_.trajectory.states : nullptr);
  // A failed trial point is routine (the trust region shrinks); -v=1 says why.
  if (!ok) {
    VLOG(1) << "segment rows " << first_ << ".." << last_
            << (sensitivities ? " (with sensitivities)" : "") << ": " << simulator.last_error();
    last_failure_ = simulator.last_error();
  } else {
    last_failure_.clear();
  }
  if (times_) {
    const long ns =
        std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - run_start).count();
    (sensitivities ? times_->sensitivity_runs : times_->state_runs) += 1;
    (sensitivities ? times_->sensitivity_ns : times_->state_ns) += ns;
  }
  if (sensitivities) {
    plain_run_.trajectory.times = trajectory.times;
    plain_run_.trajectory.states = trajectory.states;
    plain_run_.trajectory.inputs = trajectory.inputs;
    plain_run_.trajectory.sensitivities.clear();
  }
  plain_run_.ok = ok;
  plain_run_.integrated = !sensitivities;
  plain_run_.start_state = Eigen::Map<const Eigen::VectorXd>(start_state, n_);
  plain_run_.theta_scaled = Eigen::Map<const Eigen::VectorXd>(theta_scaled, free_.size());
  plain_run_.valid = true;
  return ok ? &trajectory : nullptr;
}

bool FlightSegmentCost::Predict(const double* start_state, const double* theta_scaled,
                                std::vector<Eigen::VectorXd>* outputs, Eigen::VectorXd* end_state,
                                std::vector<Eigen::VectorXd>* states) const {
  const Trajectory* trajectory = Simulate(start_state, theta_scaled, false);
  if (!trajectory) return false;
  const Eigen::VectorXd theta = free_.Theta(theta_scaled);
  outputs->clear();
  const int end = has_next_ ? last_ - 1 : last_;
  for (int k = first_; k <= end; ++k) {
    Eigen::VectorXd y(kNumFlightChannels);
    const Eigen::VectorXd& x = trajectory->states[k - first_];
    FlightOutputsAt(model_, theta.data(), x.data(), trajectory->inputs[k - first_], y.data());
    outputs->push_back(y);
  }
  if (states) {
    states->assign(trajectory->states.begin(), trajectory->states.begin() + (end - first_ + 1));
  }
  *end_state = trajectory->states.back();
  return true;
}

bool FlightSegmentCost::Evaluate(double const* const* parameters, double* residuals,
                                 double** jacobians) const {
  const int P = free_.size();
  const bool want_state = jacobians && jacobians[0];
  const bool want_theta = jacobians && jacobians[1];
  const bool want_next = jacobians && has_next_ && jacobians[2];
  const bool sensitivities = want_state || want_theta;
  const Eigen::VectorXd theta = free_.Theta(parameters[1]);
  const Trajectory* simulated = Simulate(parameters[0], parameters[1], sensitivities);
  if (!simulated) return false;
  const Trajectory& trajectory = *simulated;
  if (sensitivities) CHECK_EQ(trajectory.sensitivities.front().cols(), n_ + P);
  struct OutputTimer {
    SegmentCostTimes* times;
    std::chrono::steady_clock::time_point start;
    ~OutputTimer() {
      if (times) {
        times->outputs_ns += std::chrono::duration_cast<std::chrono::nanoseconds>(
                                 std::chrono::steady_clock::now() - start)
                                 .count();
      }
    }
  } output_timer{times_, std::chrono::steady_clock::now()};
  const int num_residuals = this->num_residuals();
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J_state(
      want_state ? jacobians[0] : nullptr, want_state ? num_residuals : 0, n_);
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J_theta(
      want_theta ? jacobians[1] : nullptr, want_theta ? num_residuals : 0, P);

  double y[kNumFlightChannels];
  // The accelerometer, and every channel under a measurement effect (a gyro
  // bias), needs the output model, and its sensitivities
  // dy = dy/dx S + dy/dtheta [0 | I] (FlightOutputTangents: S's state
  // columns, then its parameter columns); plain states are read directly.
  Eigen::MatrixXd dy, theta_tangents;
  if (sensitivities) {
    theta_tangents.setZero(P, n_ + P);
    theta_tangents.rightCols(P).setIdentity();
  }
  const bool states_are_logged = !model_.ChangesFlightMeasurements();
  size_t term = 0;
  for (int k : rows_) {
    const int i = k - first_;
    const Eigen::VectorXd& x = trajectory.states[i];
    bool needs_model = !states_are_logged;
    for (size_t t = term; t < terms_.size() && terms_[t].row == k; ++t) {
      needs_model = needs_model || terms_[t].channel >= kNumStates;
    }
    if (needs_model) {
      const bool ok =
          sensitivities
              ? FlightOutputTangents(model_, theta, x.data(), trajectory.inputs[i],
                                     free_.indices(), trajectory.sensitivities[i],
                                     theta_tangents, y, &dy)
              : FlightOutputJacobians(model_, theta, x.data(), trajectory.inputs[i],
                                      free_.indices(), y, nullptr, nullptr);
      if (!ok) return false;
    } else {
      for (int s = 0; s < kNumStates; ++s) y[s] = x[s];
    }
    for (; term < terms_.size() && terms_[term].row == k; ++term) {
      const Term& t = terms_[term];
      const double weight = column_weight_[t.column];
      residuals[term] = weight * (y[t.channel] - log_.values(k, t.column));
      if (!sensitivities) continue;
      const Eigen::MatrixXd& S = trajectory.sensitivities[i];  // n x (n + P)
      if (t.channel < kNumStates && states_are_logged) {
        if (want_state) J_state.row(term) = weight * S.block(t.channel, 0, 1, n_);
        if (want_theta) {
          J_theta.row(term) =
              weight * S.block(t.channel, n_, 1, P).cwiseProduct(free_.scales().transpose());
        }
      } else {
        if (want_state) J_state.row(term) = weight * dy.row(t.channel).head(n_);
        if (want_theta) {
          J_theta.row(term) =
              weight * dy.row(t.channel).tail(P).cwiseProduct(free_.scales().transpose());
        }
      }
    }
  }
  if (has_next_) {
    const int base = static_cast<int>(terms_.size());
    const Eigen::VectorXd& x_end = trajectory.states.back();
    for (int s = 0; s < n_; ++s) {
      residuals[base + s] = continuity_weight_ * (x_end[s] - parameters[2][s]);
    }
    if (sensitivities) {
      const Eigen::MatrixXd& S = trajectory.sensitivities.back();
      if (want_state) {
        J_state.block(base, 0, n_, n_) = continuity_weight_ * S.leftCols(n_);
      }
      if (want_theta) {
        J_theta.block(base, 0, n_, P) =
            continuity_weight_ * S.rightCols(P) * free_.scales().asDiagonal();
      }
    }
    if (want_next) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J_next(
          jacobians[2], num_residuals, n_);
      J_next.setZero();
      J_next.block(base, 0, n_, n_) = -continuity_weight_ * Eigen::MatrixXd::Identity(n_, n_);
    }
  }
  for (int r = 0; r < num_residuals; ++r) {
    if (!std::isfinite(residuals[r])) return false;
  }
  return true;
}

BalanceRowsCost::BalanceRowsCost(const VehicleModel& model, const FreeParameters& free,
                                 const EstimationLog& log, int first, int end,
                                 const std::vector<double>& channel_std)
    : model_(model), free_(free), log_(log) {
  for (int a = first; a < end;) {
    int b = a + 1;
    while (b < end && log.inputs.input(b) == log.inputs.input(a)) ++b;
    for (int c = 0; c < log.NumChannels(); ++c) {
      double sum = 0;
      int n = 0;
      for (int k = a; k < b; ++k) {
        if (std::isfinite(log.values(k, c))) {
          sum += log.values(k, c);
          ++n;
        }
      }
      if (n > 0) terms_.push_back({a, log.channels[c], c, n, std::sqrt(n) / channel_std[c], sum / n});
    }
    a = b;
  }
  set_num_residuals(static_cast<int>(terms_.size()));
  mutable_parameter_block_sizes()->push_back(free.size());
}

void BalanceRowsCost::SetChannelStd(const std::vector<double>& channel_std) {
  for (Term& t : terms_) t.weight = std::sqrt(t.count) / channel_std[t.column];
}

bool BalanceRowsCost::Evaluate(double const* const* parameters, double* residuals,
                               double** jacobians) const {
  const int P = free_.size();
  const bool want = jacobians && jacobians[0];
  const Eigen::VectorXd theta = free_.Theta(parameters[0]);
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> J(
      want ? jacobians[0] : nullptr, want ? num_residuals() : 0, P);
  double y[kNumBalanceChannels];
  Eigen::MatrixXd dydp;
  int current_row = -1;
  for (size_t term = 0; term < terms_.size(); ++term) {
    const Term& t = terms_[term];
    if (t.row != current_row) {
      current_row = t.row;
      if (!BalanceOutputJacobians(model_, theta, log_.inputs.input(t.row), free_.indices(), y,
                                  want ? &dydp : nullptr)) {
        return false;
      }
    }
    residuals[term] = t.weight * (y[t.channel] - t.mean);
    if (want) J.row(term) = t.weight * dydp.row(t.channel).cwiseProduct(free_.scales().transpose());
  }
  return true;
}

}  // namespace coaxid
