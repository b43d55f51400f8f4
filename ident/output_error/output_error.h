// Nonlinear output-error estimation of every free parameter of a vehicle
// (model.md's unknowns and any enabled effect's parameters) jointly from one
// or several logs, balance and flight mixed, with Ceres.
//
// Flight logs: the 6-DoF model integrated with CVODE over the logged inputs,
// by multiple shooting (the open-loop hover is unstable, so one long
// simulation diverges): each log is cut into segments whose initial states
// are estimated with the parameters, tied together by continuity residuals.
// The segments start short and grow (coarse-to-fine, default 0.25 s then
// 1 s), which keeps the fit out of wrong minima from a nominal start.
// Balance logs: the static load model (eqs. 57-63) as residual blocks of the
// same problem. Residuals are weighted by the channel noise std, re-estimated
// from the residuals between solves (the classical output-error relaxation).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "core/cores.h"
#include "core/parameters.h"
#include "core/statistics.h"
#include "dynamics/integrator.h"
#include "dynamics/simulator.h"
#include "dynamics/vehicle.h"
#include "ident/estimation_log.h"
#include "ident/identifiability.h"
#include "ident/noise_weights.h"
#include "ident/output_error/spare_threads.h"
#include "ident/parameter_prior.h"
#include "ident/scale_gauge.h"

namespace coaxid {

// One flight log's fitted multiple-shooting segments.
struct FittedSegments {
  std::vector<int> starts;                  // segment start rows; the last row ends the last one
  std::vector<Eigen::VectorXd> states;      // estimated start state of each segment
};

struct OutputErrorOptions {
  // Multiple-shooting segment lengths [s], one solve per entry, coarse to fine.
  std::vector<double> segment_schedule_s{0.25, 1.0};
  int max_iterations = 100;        // per solve at the final segment length
  // The coarse stages only bring the start into the right basin: a few
  // iterations and a loose stopping rule.
  int coarse_max_iterations = 15;
  double coarse_function_tolerance = 1e-4;
  // Re-estimate the noise std from the residuals and solve again this many times.
  int noise_relaxations = 2;
  // ... stopping earlier once no channel's std changes by more than this
  // fraction (the weights have converged).
  double noise_relaxation_tolerance = 0.05;
  // Gaussian priors (ident/parameter_prior.h): the fit starts at their values
  // and adds (value - mean) / std residuals; on the scale group they fix the
  // scale.
  std::vector<ParameterPrior> priors;
  // Without a balance log or prior fixing the scale, hold d (model.md
  // decision 8; ident/scale_gauge.h), or with kNone leave every member free.
  ScaleAnchor scale_anchor = ScaleAnchor::kHubDistance;
  // Solve with the scale free and move the solution onto the held value
  // afterwards (see FitOutputError). false: the held member stays held in
  // the solve too, so a member that the data push out of its bounds meets
  // its bound inside the fit instead of failing the move (discover's
  // fallback: a declared fit that needs such values is a symptom, effects.md
  // step 7).
  bool scale_free_in_solve = true;
  // Start (and, with noise_relaxations = 0, keep) these noise std; empty: from the data.
  NoiseWeights noise;
  // A warm start's segment states: a previous fit's result.segments (per log)
  // and the names of its model's states (VehicleModel::StateNames). The
  // first stage starts each segment that begins at a row given there from
  // that state, matched by name (a state the previous model lacked, such as
  // a candidate effect's, at rest); every other segment from the
  // measurements. Empty: every segment from the measurements. A refit of a
  // model nested in the new one, from the previous fit's parameters and
  // segments, then starts exactly at the previous fit.
  std::vector<FittedSegments> start_segments;
  std::vector<std::string> start_segment_state_names;
  // A continuation's solver state: the parameters a previous fit ended with
  // held at their bounds (result.held_at_bounds; those still at a bound
  // start held, ident/output_error/active_bounds.h), and its trust region
  // (result.trust_region_radius; 0: Ceres' default, 1e4), for the first
  // solve.
  std::vector<std::string> start_held_at_bounds;
  double initial_trust_region_radius = 0;
  // Continuity residual scale [state units] of the final and of the coarse
  // stages. Small, so segments join up; not tiny, because a stiff penalty
  // makes Levenberg-Marquardt crawl (measured: 1e-4 took 100+ iterations
  // where 1e-2 coarse / 2e-3 final take ~20, for estimates within 0.2 std).
  double continuity_std = 2e-3;
  double coarse_continuity_std = 1e-2;
  // > 0: Huber loss on the output residuals at this many std (robust fit).
  double huber_threshold = 0;
  // Correct the Cramér-Rao bounds for autocorrelated output residuals
  // (Morelli & Klein; ident/output_error/information.h), summing the
  // residual correlation up to coloured_max_lag samples at most.
  bool coloured_residual_correction = false;
  int coloured_max_lag = 200;
  IntegratorOptions integrator = DefaultIntegrator();
  // The coarse stages' integrator: they only bring the start into the right
  // basin, and their solution is refined at `integrator`'s accuracy, so a
  // looser tolerance serves (a pass with sensitivities costs 40 % less at
  // rtol 1e-5 than at 1e-7, bench/output_error_bench FlightPass).
  IntegratorOptions coarse_integrator = CoarseIntegrator();
  // How the segments' sensitivities (the Jacobian) are integrated
  // (dynamics/simulator.h). The residuals, and so the optimum, do not depend
  // on it; one RK4 step per hold costs less than the variational equations
  // on the integrator's steps (bench/experiments/simulation/flight_bench).
  SensitivityMethod sensitivity_method = SensitivityMethod::kRungeKuttaPerHold;
  // Threads for the segments' simulations: every core. A fit's result does
  // not depend on it (each segment is the same whichever thread computes
  // it, and Ceres adds them in one fixed order); a study's runs take one
  // each (experiments/studies/run.cc).
  int num_threads = NumCores();
  // Threads that fits side by side with this one have finished with, lent
  // to its segment evaluations (spare_threads.h); nullptr: none.
  std::shared_ptr<SpareThreads> spare_threads;
  int balance_rows_per_block = 512;
  // Ceres stopping rules. A relative cost change of 1e-7 is far below what one
  // standard deviation of any parameter changes the cost by (0.5 / cost).
  double function_tolerance = 1e-9, parameter_tolerance = 1e-10, gradient_tolerance = 1e-12;
  // Progress lines (iteration, cost, elapsed); nullptr for none. Library code
  // does not print: the CLI passes a function that writes to stderr.
  std::function<void(const std::string&)> progress;

  static IntegratorOptions DefaultIntegrator() {
    IntegratorOptions o;
    o.method = IntegratorOptions::Method::kExplicitRungeKutta;
    o.relative_tolerance = 1e-7;
    o.absolute_tolerance = 1e-9;
    o.sensitivity_error_control = false;
    // A wild trial step (blown-up parameters) fails fast instead of grinding.
    // One Dormand-Prince step covers a 5 ms hold of a vehicle inside the
    // bounds; 50 still take a mode 50 times faster than the stabilizer
    // bar's fastest (T_b = 1 ms) and refuse a non-physical one (measured,
    // seed 20468 of bench/discover_speed.sh: a restart's wild point, its
    // sensitivities on the variational equations, took discover's
    // restarts to 332 s at 500 steps, 33 s at 50, the same answer).
    o.max_steps_per_interval = 50;
    // The state by one classic RK4 step per 5 ms hold (the step the
    // sensitivities take already), the integrator only on an interval too
    // stiff for it: four right-hand sides a hold where Dormand-Prince at
    // rtol 1e-7 took 9.65 (1.21 steps a hold, failed ones and the restart
    // included; seed 20910, a whole discover run), and the state's replays
    // were about 40 % of a fit's time. Its error over a second, 8.6e-9 of
    // the state's size (simulator_test), is far below any noise. discover on
    // the 44 flight-only logs of seeds 20980-21059: 343 -> 263 s summed,
    // the largest 26.4 -> 18.8 s, the same added effects on every log
    // (docs/discover_confusion.md, twenty-seventh session).
    o.one_rk4_step_per_hold = true;
    // An interval too stiff for that step is refused, not integrated: the
    // model's modes inside the library's bounds are slow against the holds
    // (the stabilizer bar's fastest, T_b = 0.05 s, 20 / s; the lags act on
    // the held inputs, not as states), so a trial point with a mode beyond
    // 2 / h (200 / s on the 100 Hz rows discover fits) is outside the
    // physical range, where the integrator ground through up to 50 steps a
    // hold. Measured (docs/discover_confusion.md, thirty-fourth session):
    // 12 % of a discover run's holds on confusion seed 21898 went to the
    // integrator; refused, 20.7 -> 10.0 s, 21668 31.9 -> 17.1 s, the same
    // effects added.
    o.stiff_holds_fail = true;
    return o;
  }
  static IntegratorOptions CoarseIntegrator() {
    IntegratorOptions o = DefaultIntegrator();
    o.relative_tolerance = 1e-5;
    o.absolute_tolerance = 1e-7;
    return o;
  }
  bool IsValid(std::string* why) const;
};

struct OutputErrorResult {
  bool usable = false;
  std::string why_not_usable;
  // Not usable because moving the solution onto the held scale would take a
  // member out of its bounds (retry with scale_free_in_solve = false).
  bool scale_move_failed = false;
  // Solved with the held scale member held in the solve too
  // (scale_free_in_solve = false with a held member): warm refits from this
  // fit hold it as well (discover's WarmRefit).
  bool scale_held_in_solve = false;
  ParameterSet parameters;                  // estimates written back (d not estimated if held)
  IdentifiabilityReport identifiability;    // std, covariance, correlation, null directions
  ScaleGauge gauge;                         // what fixed the scale (model.md decision 8)
  std::vector<ScaleFreeRatio> ratios;       // what flight logs determine, with std
  NoiseWeights noise;                       // the weights of the final solve
  std::vector<FittedSegments> segments;     // per log (empty for balance logs)
  // Model outputs on the fitted logs: flight, predictions over each segment
  // started from its fitted state; balance, the static model. Same shape as
  // each log's values.
  std::vector<Eigen::MatrixXd> predictions;
  // With coloured_residual_correction: the white-noise std, the truncation
  // lag per flight log and corrected std / white std per parameter (the
  // identifiability report then holds the corrected std and covariance).
  struct ColouredResiduals {
    bool applied = false;
    Eigen::VectorXd white_std;
    Eigen::VectorXd factor;
    std::vector<int> lags;
    nlohmann::json ToJson(const std::vector<std::string>& names) const;
  } coloured_residuals;
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;
  std::string termination;                  // Ceres' reason for stopping
  bool hit_iteration_limit = false;         // the last solve stopped at max_iterations
  std::vector<std::string> held_at_bounds;  // held at a bound when the last solve ended
  double trust_region_radius = 0;           // the last solve's trust region at its end
  double seconds = 0;
  nlohmann::json timing;                    // where the time went
};

// Fits vehicle's free parameters to the logs (after the scale gauge: with
// flight logs alone d is held, see OutputErrorOptions::scale_anchor). Throws InputError for invalid
// options or logs that cannot be used (too short for one segment), and
// returns usable = false (with the reason) when the solve fails.
OutputErrorResult FitOutputError(const Vehicle& vehicle, const std::vector<EstimationLog>& logs,
                                 const OutputErrorOptions& options);

// The precision an output-error fit would have on logs of a planned
// experiment, before it is flown (experiment design): the Fisher information
// M of the same multiple-shooting problem (segments of the schedule's last
// length, continuity residuals, balance blocks, priors, the scale gauge)
// evaluated at the vehicle's parameter values with the segments started on
// the true trajectory, weighted by the planned sensors' noise std.
//
// M^-1 is the Cramér-Rao bound a fit of such logs reports. The fit's
// continuity residuals enter M as if they were measurements of std
// continuity_std, but no noise drives them: the spread of the estimates
// over noise seeds is the sandwich M^-1 D M^-1, D the information of the
// rows that do carry measurement noise (flight outputs with the segment
// states marginalised, balance holds, priors). The bound is larger, most
// for the parameters the segment states can stand in for (Cz from a
// near-hover flight: 1.4x).
struct PredictedPrecision {
  ParameterSet parameters;                // the vehicle's, d marked held when the gauge holds it
  ScaleGauge gauge;
  std::vector<std::string> names;         // the free parameters
  Eigen::VectorXd scales;                 // their scales (information coordinates value / scale)
  Eigen::MatrixXd information_scaled;     // M, P x P, priors included
  Eigen::MatrixXd measured_scaled;        // D
  IdentifiabilityReport identifiability;  // the predicted spread: std, covariance, correlation
  Eigen::VectorXd bound_std;              // sqrt(diag M^-1), unscaled: what a fit reports
  std::vector<ScaleFreeRatio> ratios;     // with their predicted std (no balance log)
};

// true_states[i]: the true state at every row of flight log i (empty for a
// balance log). Throws InputError on logs that cannot be fitted and
// ComputationError when the model cannot be simulated along them.
PredictedPrecision PredictOutputErrorPrecision(
    const Vehicle& vehicle, const std::vector<EstimationLog>& logs,
    const std::vector<std::vector<Eigen::VectorXd>>& true_states, const NoiseWeights& noise,
    const OutputErrorOptions& options);

// The same precision from information already computed (M and D as above):
// identifiability, bound and ratios of `base` recomputed.
PredictedPrecision WithInformation(const PredictedPrecision& base,
                                   const Eigen::MatrixXd& information_scaled,
                                   const Eigen::MatrixXd& measured_scaled);

// report.json "parameters" of a fit: {"name": {"value", "std", "estimated",
// "unit"}} for every parameter; a parameter the data do not determine gets
// "std": null and "identifiable": false, the one held for the scale is
// marked so.
nlohmann::json ParametersJson(const OutputErrorResult& result);

// Model predictions for logs with the parameters fixed (held-out validation):
// balance logs through the static model; flight logs over consecutive windows
// of window_s, each started from a state estimated on that window alone with
// the parameters held fixed (an honest validation for an unstable plant).
// A hold too stiff for the fits' RK4 step is integrated, not refused
// (options.integrator.stiff_holds_fail is not applied).
std::vector<Eigen::MatrixXd> PredictWithFixedParameters(const Vehicle& vehicle,
                                                        const std::vector<EstimationLog>& logs,
                                                        const NoiseWeights& noise,
                                                        double window_s,
                                                        const OutputErrorOptions& options);

// Per-channel fit errors of predictions against the logs' values.
std::map<std::string, FitError> ChannelFitErrors(const std::vector<EstimationLog>& logs,
                                                 const std::vector<Eigen::MatrixXd>& predictions);

// The state at a row from the log's measurements: measured states where
// present, velocity from differenced position where u, v, w are missing,
// zero otherwise.
Eigen::VectorXd InitialStateFromLog(const EstimationLog& log, int row);

}  // namespace coaxid
