// The residual blocks of the output-error problem (Ceres cost functions).
//
// FlightSegmentCost, one multiple-shooting segment [first, last] of a flight
// log, parameter blocks (s_j [12], theta_scaled [P] [, s_j+1 [12]]):
//   r(k, c) = (h_c(x_k, u_k, theta) - y(k, c)) / std_c   for rows first..end,
//   r_cont  = (x(t_last; s_j, theta) - s_j+1) / continuity_std,
// where x_k comes from CVODE started at x(t_first) = s_j over the logged
// zero-order-hold inputs, h is the flight output model (dynamics/outputs.h),
// and the Jacobians come from the sensitivities dx_k/d[s_j, theta] chained
// with the autodiff Jacobians of h. Rows end at last - 1, or at last for the
// final segment of a log (the next segment owns row `last`).
//
// BalanceRowsCost, a chunk of balance-log rows, parameter block (theta_scaled):
//   r(k, c) = (h_c(u_k, theta) - y(k, c)) / std_c
// with h the balance output model and its autodiff Jacobian. Consecutive rows
// with identical inputs (a constant-input hold) have the same model output,
// so their squared residuals sum to n_c (h_c - mean_c)^2 / std_c^2 plus a
// constant: each hold enters as one residual sqrt(n_c) (h_c - mean_c) / std_c
// per channel, which gives the same estimates and Fisher information with a
// hold's worth fewer evaluations.
//
// Both return false (Ceres rejects the step) when the model cannot be
// evaluated: CVODE failure, non-finite values.
//
// A FlightSegmentCost keeps the states of its last simulation and reuses
// them when asked for residuals at the same (s_j, theta) again (the
// predictions at the solution; a trial point's residuals after the
// Jacobian's run there). Sensitivities are not kept: a 1 s segment's are
// 0.5 MB; Ceres gets the segment through CompressedSegmentCost, which keeps
// its compressed Jacobian instead. The channel weights are not part of the
// cached simulation, so they can change between solves (SetChannelStd)
// without a new CVODE run.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <ceres/ceres.h>

#include "dynamics/simulator.h"
#include "dynamics/simulator_pool.h"
#include "dynamics/vehicle_model.h"
#include "ident/estimation_log.h"
#include "ident/free_parameters.h"

namespace coaxid {

// Where the flight residual blocks spend their time, summed over the threads
// that evaluate blocks concurrently (so it can exceed the wall time): CVODE
// runs of the state alone, runs with sensitivities, and the rest (output
// model, its Jacobians, chaining them with the sensitivities).
struct SegmentCostTimes {
  std::atomic<long> state_runs{0}, state_ns{0};
  std::atomic<long> sensitivity_runs{0}, sensitivity_ns{0};
  std::atomic<long> outputs_ns{0};
};

// The simulators of the segments of one problem, without and with
// sensitivities to [s_j | the free parameters]: as many as run at once.
struct SegmentSimulators {
  SegmentSimulators(const VehicleModel& model, const FreeParameters& free,
                    const IntegratorOptions& integrator,
                    SensitivityMethod method = SensitivityMethod::kRungeKuttaPerHold);
  mutable SimulatorPool plain, sensitive;
};

class FlightSegmentCost : public ceres::CostFunction {
 public:
  // channel_std[c]: noise std of log channel c. path: the log's rows as
  // applied, shared by its segments (null: each segment walks the log's
  // lags itself). All references must outlive the cost.
  // simulators: shared by the segments of one problem (null: the segment
  // makes its own).
  FlightSegmentCost(const VehicleModel& model, const FreeParameters& free, const EstimationLog& log,
                    int first, int last, bool has_next, const std::vector<double>& channel_std,
                    double continuity_std, const IntegratorOptions& integrator,
                    const HeldInputPath* path = nullptr,
                    std::shared_ptr<const SegmentSimulators> simulators = nullptr);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  // New noise std per log channel (the output-error relaxation).
  void SetChannelStd(const std::vector<double>& channel_std);

  // Accumulate evaluation times there (may be null; must outlive the cost).
  void set_times(SegmentCostTimes* times) { times_ = times; }

  int first() const { return first_; }
  int last() const { return last_; }
  bool has_next() const { return has_next_; }
  // Why the segment's last simulation failed (the simulator's message);
  // empty if it did not.
  const std::string& last_failure() const { return last_failure_; }
  int NumOutputResiduals() const { return static_cast<int>(terms_.size()); }

  // Output residual r of Evaluate is terms()[r]; the continuity residuals
  // (if has_next) follow them.
  struct Term {
    int row;             // log row
    std::int16_t column;   // log channel column
    std::int16_t channel;  // FlightChannel
  };
  const std::vector<Term>& terms() const { return terms_; }

  // The model's outputs (15 flight channels) at rows first..end and the state
  // at `last`, for given segment start state and scaled parameters; with
  // `states`, the states (effect states included) at rows first..end too.
  // False if the simulation fails.
  bool Predict(const double* start_state, const double* theta_scaled,
               std::vector<Eigen::VectorXd>* outputs, Eigen::VectorXd* end_state,
               std::vector<Eigen::VectorXd>* states = nullptr) const;

 private:
  const VehicleModel& model_;
  const FreeParameters& free_;
  const EstimationLog& log_;
  const HeldInputPath* path_;
  int first_, last_;
  int n_;  // the model's states (effect states after the 12): a segment's start block
  bool has_next_;
  double continuity_weight_;
  std::vector<double> column_weight_;  // 1 / noise std per log channel column
  std::vector<Term> terms_;
  std::vector<int> rows_;  // distinct rows with terms, ascending
  // The trajectory from start_state with theta_scaled (with sensitivities if
  // asked), from the cache when the last run at that point is there; null if
  // the simulation fails.
  const Trajectory* Simulate(const double* start_state, const double* theta_scaled,
                             bool sensitivities) const;
  struct CachedRun {
    bool valid = false, ok = false;
    // The states are the integrator's alone (a run without sensitivities):
    // not those of a run whose sensitivities fell back to the variational
    // equations, which set the state too.
    bool integrated = false;
    Eigen::VectorXd start_state, theta_scaled;
    Trajectory trajectory;
    bool At(const double* start_state, const double* theta_scaled) const;
  };
  // The simulators, and the states of the last run; Ceres may evaluate
  // different blocks in parallel but never one block twice at once.
  std::shared_ptr<const SegmentSimulators> simulators_;
  mutable CachedRun plain_run_;
  mutable std::string last_failure_;
  SegmentCostTimes* times_ = nullptr;
};

class BalanceRowsCost : public ceres::CostFunction {
 public:
  BalanceRowsCost(const VehicleModel& model, const FreeParameters& free, const EstimationLog& log,
                  int first, int end, const std::vector<double>& channel_std);
  // New noise std per log channel (the output-error relaxation).
  void SetChannelStd(const std::vector<double>& channel_std);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  struct Term {
    int row, channel;  // a row of the hold (its inputs), the BalanceChannel
    int column;        // the log channel column
    int count;         // n, the hold's finite values of the channel
    double weight;     // sqrt(n) / std
    double mean;       // mean of the hold's finite values of the channel
  };
  const VehicleModel& model_;
  const FreeParameters& free_;
  const EstimationLog& log_;
  std::vector<Term> terms_;
};

}  // namespace coaxid
