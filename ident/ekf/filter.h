// The filter of ekf.h one log row at a time: the predict step (CVODE over
// the hold interval, P <- Phi P Phi^T + Qd) and the update step (gate,
// Cholesky of S, Joseph form), with everything that decides the next rows
// held in one EkfFilterState that can be saved and restored. The pass over
// the logs (pass.h) and the smoother's recomputation of a block from a
// checkpoint run these same two steps, so the recomputed rows are the
// forward pass's rows bit for bit (the filter equations exist once).
//
// Internal to ident/ekf: ekf.cc and pass.cc use it.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <deque>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "dynamics/held_input.h"
#include "dynamics/vehicle.h"
#include "ident/ekf/ekf.h"
#include "ident/ekf/model.h"
#include "ident/estimation_log.h"
#include "ident/free_parameters.h"
#include "ident/noise_weights.h"

namespace coaxid {

// What every pass shares.
struct EkfProblem {
  const Vehicle& vehicle;
  const std::vector<EstimationLog>& logs;
  NoiseWeights noise;
  const EkfOptions& options;
  const FreeParameters& free;
  Eigen::VectorXd lower, upper;  // scaled bounds
  Eigen::VectorXd qp;            // parameter random walk, scaled
  Eigen::MatrixXd prior;         // parameter prior covariance, scaled
  EkfState qx;  // the model's states' process noise (EkfOptions::state_psd, effect_state_psd)
  long total_rows = 0;  // over every pass, for progress
};

struct ChannelAccumulator {
  double nis = 0, innovation_squares = 0, innovation_variance = 0;  // sums of nu^2/S, nu^2, S
  long count = 0;
};

// What the updates of a pass count. Rows the smoother recomputes count nothing.
struct EkfTally {
  bool innovations = false;  // count the innovation statistics and gate rejections too
  std::map<std::string, ChannelAccumulator> channel_stats;
  std::map<std::string, long> rejected;  // innovation gate: samples rejected per channel
  double total_nis = 0, log_likelihood = 0;
  long total_dof = 0, clamped = 0, updates = 0;
};

// Everything the rows after (log, row) depend on: a checkpoint.
struct EkfFilterState {
  int log = 0, row = 0;
  Eigen::VectorXd z;  // filtered [x; p] at the row
  Eigen::MatrixXd P;
  // The input as applied over the next interval (lags carried row to row).
  HeldInput held;
  // Innovation gate: since when each column of the log has been rejected (NaN: not).
  std::vector<double> rejected_since;
  // Divergence watch: (t, (nis, dof)) of the updates within the window, and their sums.
  std::deque<std::pair<double, std::pair<double, int>>> window;
  double window_nis = 0;
  long window_dof = 0;
  // CVODE's first-step hint (dynamics/integrator.h): without it a recomputed
  // interval takes other steps and differs in the last digits.
  double step_hint = 0;
  // Frozen filter (covariance pass) only: dz, how far the same filter with
  // the parameters' mean free would have moved [x; p] from this one's, to
  // first order (the linearisation along this pass). Its parameter part at
  // the end is the Gauss-Newton step of the filter's likelihood from the
  // frozen parameters (ekf.h, "Refinement").
  Eigen::VectorXd step;
};

class EkfFilter {
 public:
  // From parameters p_start (scaled) with the prior covariance; freeze: keep
  // the parameters' mean (covariance pass) and track state().step.
  // Positioned before log 0.
  EkfFilter(const EkfProblem& problem, const Eigen::VectorXd& p_start, bool freeze);

  // Moves to `row` of `log`: row 0 starts the log (its states from the row,
  // P0 = R for the states it holds, the parameters carried over); row > 0
  // predicts over [t_{row-1}, t_row) with u_{row-1}. Afterwards Phi(),
  // predicted_z(), predicted_P() give the transition from state() for the
  // smoother (at row 0: the log boundary, states restarted, parameters
  // carried), and Update() completes the row. Returns false with failure()
  // set (hot numeric code).
  bool Predict(int log, int row);
  // The update with the channels the row holds (nothing at row 0). tally:
  // where to count it (null: count nothing).
  bool Update(EkfTally* tally);
  // The last Update()'s innovations: the log's columns that took part (none:
  // no update), nu, S_jj and the NIS.
  const std::vector<int>& updated_columns() const { return present_; }
  const Eigen::VectorXd& innovations() const { return nu_; }
  Eigen::VectorXd InnovationStd() const { return S_.diagonal().cwiseSqrt(); }
  double nis() const { return nis_; }

  const EkfFilterState& state() const { return s_; }
  void Restore(const EkfFilterState& state);

  const Eigen::MatrixXd& Phi() const { return row_ == 0 ? boundary_ : phi_; }
  const Eigen::VectorXd& predicted_z() const { return z_pred_; }
  const Eigen::MatrixXd& predicted_P() const { return P_pred_; }

  // The failure in words ("EKF failed at t = ... in LOG (row R of the log): why"),
  // with its time.
  bool Fail(double t, int log, int row, const std::string& reason);
  const std::string& failure() const { return failure_; }
  double failure_time() const { return failure_time_; }

  const EkfPropagator& propagator() const { return propagator_; }

 private:
  const EkfProblem& pb_;
  const bool freeze_;
  const int nx_, np_, n_;
  EkfPropagator propagator_;
  EkfFilterState s_;
  int row_ = 0;        // the row Predict() moved to
  Eigen::VectorXd R_;  // measurement noise variance of the current log's columns
  const bool states_are_logged_;
  const bool gating_;
  const double gate_;

  // Predicted (or, at row 0, the log's initial) z and P, and the transition to them.
  Eigen::VectorXd z_pred_;
  Eigen::MatrixXd P_pred_, phi_, boundary_;
  // Workspace.
  EkfTransition transition_;
  Eigen::MatrixXd H_, HP_, PHt_, S_, K_, THt_, T_;
  Eigen::VectorXd nu_, r_diag_, step_dx_, step_h_;
  Eigen::Matrix<double, kNumFlightChannels, 1> y_hat_;
  Eigen::Matrix<double, kNumFlightChannels, Eigen::Dynamic> H_model_;
  Eigen::LLT<Eigen::MatrixXd> llt_;
  std::vector<int> present_;  // columns of the log measured (and passing the gate) in this row
  double nis_ = 0;

  std::string failure_;
  double failure_time_ = 0;
};

}  // namespace coaxid
