// Extended Kalman filter on the model's states (the 12 of dynamics/state.h,
// then any effect's own: the stabilizer bar's tilt) augmented with the free parameters,
// from flight logs: the recursive estimator for long logs and online use, and
// a second opinion on output-error (issue 5).
//
// Model (ident/ekf/model.h): continuous-discrete EKF on z = [x; p], p the
// free parameters in scaled coordinates (value / scale) as random walks (the
// paper's eq. 66 with the nonlinear 6-DoF model):
//   xdot = f(x, theta(p), u) + w_x,  pdot = w_p,  E[w w^T] = diag(q_x, q_p) delta,
//   y_k = h(x_k, theta(p), u_k) + v_k,  E[v v^T] = R = diag(noise std^2).
// Per log row k >= 1:
//   predict  CVODE over the zero-order-hold interval [t_{k-1}, t_k) with input
//            u_{k-1}; P <- Phi P Phi^T + Qd (Phi, Qd: ekf/model.h);
//   update   with the channels row k holds (NaN skipped, so channels may have
//            different rates and rows may be irregular; samples outside the
//            innovation gate skipped and counted, EkfOptions::gate_probability): innovation
//            nu = y - h(x, theta, u_k) (angles wrapped to (-pi, pi]),
//            S = H P H^T + R with each S_ii floored at R_ii, Cholesky of S
//            (never an inverse), K = P H^T S^{-1}, and the Joseph form
//            P <- (I - K H) P (I - K H)^T + K R K^T, symmetrised; parameters
//            leaving their bounds are projected back onto them (counted).
// Row 0 initialises the state (P0 = R for the channels it holds; unmeasured
// states from EkfOptions) and is not used again. The parameters start from
// the parameter set's values (the config, or an output-error report) with the
// std of EkfOptions. Several logs are chained: each restarts the states from
// its first row and carries the parameters (mean and covariance).
//
// Scale (model.md, decision 8): flight logs fix only ratios of d, gamma1,
// gamma2, Ixx, Iyy, Izz (and moment-type effect parameters). When every
// member of that group is free, the default (ScaleAnchor::kHubDistance) holds
// d at its config value and says so; the others are then estimates relative
// to that d (the ratios are reported with their std). ScaleAnchor::kNone
// augments them all: the filter then finds the undetermined direction in its
// final covariance (ekf/identifiability.h), reports it, and marks the
// parameters along it as not separately identifiable (no std is invented).
//
// Two passes (EkfOptions::covariance_pass, default on):
//  1. estimation: the filter above; its final parameters are the estimates,
//     its innovations the consistency checks (NIS), its parameter history the
//     convergence history;
//  2. covariance: the same filter again from the same prior covariance, with
//     the parameters' mean held at pass 1's estimates (their covariance is
//     updated as usual). Its final covariance is the reported one, and its
//     states (filtered and smoothed) the reported states.
// Why: a single EKF pass evaluates its Jacobians at estimates that move while
// it learns, and accumulates information that the model does not contain
// along weakly observable directions (the inconsistency known from EKF-SLAM,
// Huang, Mourikis and Roumeliotis 2010). On the simulated flight the
// interference loss sigma0 (separated from the overall alpha, beta scale only
// by the lower rotor's lateral force) came out with a single-pass std of
// 0.0054 where the profile likelihood's curvature gives 0.0137; pass 2,
// linearised at one point, gives 0.0134. With the parameters fixed in the
// mean, an unobservable direction also gets exactly no information, so it is
// detected reliably. For online use, covariance_pass = false is the plain
// recursive filter.
//
// Refinement. A single pass stops short along a direction the logs fix only
// weakly and nonlinearly: the stabilizer bar's k_b against d_u (only their
// product sets the bar's moment; k_b alone its small lateral force). On the
// GLMAV with a bar (seed 8101) pass 1 ended at k_b 0.130 +- 0.014 against a
// truth of 0.40, and pass 2's std, the curvature at that point, claimed it.
// So pass 2 also carries, row by row, how far the same linearised filter with
// the parameters' mean free would have moved them (EkfFilterState::step):
// at the end that is the Gauss-Newton step of the filter's likelihood (the
// prediction-error likelihood of the filter at fixed parameters, the
// filter-error method of Maine and Iliff 1981) from pass 1's estimate. If
// any parameter's step exceeds refine_tolerance_std of its std, the estimate
// is not the likelihood's maximum: frozen passes at estimate + step (in
// logs where the sign is fixed, refinement.h; halved while the
// likelihood does not rise and the step still exceeds the tolerance) repeat
// until the steps are below the
// tolerance, the likelihood stops rising, or max_refinements is spent, and
// the covariance pass runs again at the result. A pass 1 within the
// tolerance costs nothing more; a step of more than unconverged_step_std
// left is reported, naming the parameters it would move.
//
// Optional measurement-noise adaptation (EkfOptions::noise_adaptations): R
// re-estimated from an estimation pass's innovations before the final passes.
//
// Optional Rauch-Tung-Striebel smoother (rts_smoother.h) over the whole chain
// in the last pass: smoothed states at every row. (The parameters' smoothed
// values equal the final filtered ones up to their random walk: they are not
// kept.) Its store comes from checkpoints of the filter and recomputation
// (ekf/pass.h), so its memory grows with sqrt(rows), not with the rows.
//
// Cost (bench/ident/ekf/ekf_bench.cc, 60 s at 200 Hz, 12 unknowns augmented): per
// 5 ms row ~9 us propagation (ARKODE restarted at the input change, one
// Runge-Kutta step; one autodiff Jacobian; the exponential series) and ~8 us
// update (autodiff of the accelerometer, Cholesky, Joseph form), per pass;
// the smoother ~15 us per row, plus the recomputation of every block but the
// last (about one more pass of the filter, shared out over the cores:
// ekf/pass.h). The variational-equation transition costs ~25 us per row
// instead of 9.
//
// Memory: the filter and its smoother O(sqrt(rows)) (ekf/pass.h); the
// per-row records go to an EkfHistorySink (ekf/history_sink.h), by default
// EkfResult::logs (~1 kB a row), or streamed to files (ekf/history_files.h:
// what `coaxid identify --method=ekf` does).
//
// Failures (CVODE, a covariance that is not positive definite, non-finite
// values, or divergence: the normalised innovation squared per degree of
// freedom above EkfOptions::divergence_nis over a window) make the result
// unusable with the time and reason; they are not thrown (hot numeric code),
// the caller decides (the CLI turns them into ComputationError, exit 1).
#pragma once

#include <array>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/parameters.h"
#include "dynamics/integrator.h"
#include "dynamics/state.h"
#include "dynamics/vehicle.h"
#include "ident/ekf/identifiability.h"
#include "ident/ekf/model.h"
#include "ident/estimation_log.h"
#include "ident/noise_weights.h"
#include "ident/scale_gauge.h"

namespace coaxid {

struct EkfOptions {
  // Continuous process noise, power spectral density per state [(state unit)^2 / s]:
  // positions m^2/s, velocities (m/s)^2/s, angles rad^2/s, rates (rad/s)^2/s. It
  // stands for model error. The defaults are small: a velocity random walk of
  // 3 mm/s and a rate random walk of 3 mrad/s after 1 s, about a tenth of the
  // sensor noise per sample; the kinematic rows (positions, angles) are exact.
  // On simulated flights (no process noise in the truth) they keep the
  // normalised innovations inside their 95 % band and every parameter within
  // 2.4 std of the truth over nine seeds (tests/ident/ekf/ekf_test.cc); real
  // logs with model error need larger values (watch the NIS in the report).
  std::array<double, kNumStates> state_psd = {1e-8, 1e-8, 1e-8, 1e-5, 1e-5, 1e-5,
                                              1e-8, 1e-8, 1e-8, 1e-5, 1e-5, 1e-5};
  // The same for the states an effect owns (the stabilizer bar's tilt, rad^2/s):
  // 1e-6, a random walk of 1 mrad after 1 s, for a first-order model of a bar
  // whose real motion is not quite first order.
  double effect_state_psd = 1e-6;
  // Random walk of the scaled parameters [(scaled unit)^2 / s]: 1e-10 lets a
  // parameter wander by 1e-4 of its scale over 100 s (constant in practice,
  // but never a singular process covariance). Overrides by name.
  double parameter_psd = 1e-10;
  std::map<std::string, double> parameter_psd_by_name;
  // Initial std of each free parameter, in scaled units (0.5: half the
  // parameter's typical magnitude, the config's `scale`). Overrides by name,
  // in the parameter's own units (e.g. from an output-error report).
  double initial_parameter_std = 0.5;
  std::map<std::string, double> initial_parameter_std_by_name;
  // Initial std of states the first row does not hold (their value: 0).
  double initial_position_std = 10.0;  // m
  double initial_velocity_std = 1.0;   // m/s
  double initial_angle_std = 0.5;      // rad
  double initial_rate_std = 1.0;       // rad/s
  // Initial std of an effect's own states (not logged; their value: 0, at
  // rest), in their units (the bar's tilt: rad). 0.01: a log that starts in
  // hover. Larger values let the first rows' accelerometer noise into the
  // bar's tilt, whose product with the rotor thrust then drags alpha and
  // beta (measured, CoaX flight, seed 3200, bar known: at 0.05 rad alpha
  // reached its bound within 0.1 s and the filter lost az at 0.29 s; at 0.01
  // and 0.002 it ran through).
  double initial_effect_state_std = 0.01;

  EkfTransitionMethod transition = EkfTransitionMethod::kLinearised;
  // Longest interval linearised at once [s]; longer ones are split.
  double max_substep_s = 0.01;
  // CVODE for the mean (and the sensitivities with kSensitivities).
  IntegratorOptions integrator = DefaultIntegrator();

  bool covariance_pass = true;  // see the header comment
  // Refinement (header comment): at most this many Gauss-Newton steps of the
  // filter's likelihood after pass 1 (0: none), until no parameter's step
  // exceeds refine_tolerance_std of its std. 2: steps of 1.1-1.7 std are
  // the filter's own linearisation error, the likelihood falls along them
  // (measured: the shipped flights 1.15 and 1.24; EkfTest's Monte Carlo
  // flights, seeds 32 and 36, 1.10 and 1.56; the 60-minute flight after one
  // refinement 1.7), and each such trial is a whole pass for nothing.
  int max_refinements = 10;
  double refine_tolerance_std = 2.0;
  // A step that does not raise the likelihood (refinement.h) at any
  // length above the tolerance ends the refinement; the estimate counts as
  // converged if that step is at most this many std (measured: 1.1-1.2 on
  // the shipped flights; 5.5 on the CoaX flight with the bar started at
  // T_b 1.0, k_b 0.3 against 1.8, 0.6, where pass 1 stopped 5 std short).
  double unconverged_step_std = 3.0;
  // Re-estimate the measurement noise from the innovations (Mehra 1970:
  // R_ii = mean(nu_i^2 - (H P H^T)_ii) after the burn-in) this many times,
  // each time with a full estimation pass, before the final passes. The
  // first-difference estimate (NoiseFromData) overstates R where a channel
  // moves between samples (the yaw rate by 2x in variance on the shipped
  // flight), which makes every std too large and the NIS too small.
  int noise_adaptations = 0;
  // Rows (of the chained logs, from the first) each noise-adaptation pass runs over; 0: all.
  // 120,000 rows (10 minutes at 200 Hz) give each channel's variance to ~0.4 % (1/sqrt(n/2)),
  // far below what moves an estimate, and spare a long log most of a pass (an hour at 200 Hz:
  // 11 s of the EKF's 60 s).
  long noise_adaptation_rows = 120000;
  bool smoother = true;
  // Rows per block of the smoother's checkpoints (ekf/pass.h): the forward
  // pass keeps the filter state every this many rows and the backward pass
  // recomputes one block at a time. 0: about sqrt(rows), at least 256 (memory
  // O(sqrt(rows)), one more forward pass in time); at least the rows: the
  // whole store in memory, nothing recomputed. The smoothed states are the
  // same either way.
  long smoother_block_rows = 0;

  // ident/scale_gauge.h. A parameter with initial_parameter_std_by_name is a
  // prior: on a member of the scale group it fixes the scale.
  using ScaleAnchor = coaxid::ScaleAnchor;
  ScaleAnchor scale_anchor = ScaleAnchor::kHubDistance;

  // Consistency statistics skip the first nis_burn_in_s of each log [s].
  double nis_burn_in_s = 5.0;
  // Divergence: mean NIS per degree of freedom over the last divergence_window_s
  // above this (expected 1).
  double divergence_nis = 1000.0;
  double divergence_window_s = 1.0;
  // A direction counts as undetermined if the logs reduced its variance by
  // less than this factor (final / prior variance above it).
  double undetermined_variance_ratio = 0.5;

  // Innovation gate (glitch rows of real logs): a sample whose normalised
  // innovation nu^2 / S (its own channel, S = (H P H^T)_jj + R_jj) exceeds
  // the chi-square(1) quantile that a consistent filter passes with
  // probability 1 - gate_probability is dropped from the update and counted
  // per channel (EkfResult::rejected). 1e-6 (4.9 std): on a 60 s 200 Hz log
  // of 15 channels about 0.2 good samples are rejected; 0 turns the gate off.
  // A channel rejected for longer than gate_max_s without a break is not
  // glitching (a sensor fault or step, or a filter that has lost it): the
  // filter fails with the channel, the time and what to change.
  double gate_probability = 1e-6;
  double gate_max_s = 0.25;

  // Progress: called every progress_every_rows rows (rows done, rows in all).
  std::function<void(long, long)> progress;
  long progress_every_rows = 2000;

  bool IsValid(std::string* why) const;

  // rtol 1e-5: the integration error per 5 ms interval (~1e-6 m/s, 1e-7 rad/s)
  // is two orders below the process noise per interval (sqrt(q dt) ~ 2e-4).
  // Measured on a simulated 60 s flight with CVODE's Adams: 1e-6 costs 10 %
  // more propagation time for a log-likelihood change of 0.1; 1e-4 saves 25 %
  // but changes it by 7. ARKODE's explicit Runge-Kutta: one step covers an
  // interval, more accurate than Adams at the same tolerances
  // (dynamics/integrator.h), and 15 % less time a propagated interval
  // (bench/ident/ekf/ekf_bench.cc).
  static IntegratorOptions DefaultIntegrator() {
    IntegratorOptions o;
    o.method = IntegratorOptions::Method::kExplicitRungeKutta;
    o.relative_tolerance = 1e-5;
    o.absolute_tolerance = 1e-7;
    o.sensitivity_error_control = false;
    return o;
  }
};

// Consistency of one channel's (or all channels') innovations: the mean
// normalised innovation squared per degree of freedom and its two-sided 95 %
// band under the chi-square law (a consistent filter: mean 1).
struct NisStatistic {
  std::string channel;   // a channel name, or "all"
  long dof = 0;          // degrees of freedom summed (samples for one channel)
  double mean = 0;       // sum NIS / dof
  double lower = 0, upper = 0;  // 95 % band of that mean
  double innovation_rms = 0;    // one-step-ahead prediction error (channel only)
  bool consistent() const { return dof > 0 && mean >= lower && mean <= upper; }
};
// [lower, upper] of sum / dof for a chi-square(dof) sum, two-sided
// `confidence` (Wilson-Hilferty; relative error < 1e-3 for dof >= 10).
std::pair<double, double> ChiSquareMeanBand(double dof, double confidence = 0.95);
// The innovation gate's threshold on nu^2 / S: the chi-square(1) quantile at
// 1 - probability (EkfOptions::gate_probability > 0).
double InnovationGateThreshold(double probability);

struct EkfLogHistory {
  std::string source, name;
  // The log rows held, when this is a thinned copy (the plots of a long log,
  // ekf/history_files.h); empty: every row.
  std::vector<int> rows;
  std::vector<double> times;
  std::vector<int> channels;               // FlightChannel of each measured column
  std::vector<std::string> channel_names;
  Eigen::MatrixXd measured;                // rows x channels (NaN missing): the log's values
  // The model's states (VehicleModel::StateNames: "x" ... "r", then any
  // effect's own, "stabilizer_bar.b_x").
  std::vector<std::string> state_names;
  // The reported state estimates (rows x states), from the last pass (with the
  // covariance pass: at the final parameters): filtered, and smoothed (empty
  // without the smoother).
  Eigen::MatrixXd states, state_std;
  Eigen::MatrixXd smoothed_states, smoothed_state_std;
  // The recursive parameter estimates of pass 1 and their filter std (rows x
  // np, physical units): the convergence history.
  Eigen::MatrixXd parameters, parameter_std;
  // The covariance pass's std at the final estimates (rows x np; empty without it).
  Eigen::MatrixXd parameter_std_at_estimate;
  // Pass 1's one-step-ahead innovations (rows x channels, NaN where not
  // measured and at row 0), sqrt(S_ii), and NIS per row.
  Eigen::MatrixXd innovations, innovation_std;
  std::vector<double> nis;  // NaN where no update
  std::vector<int> nis_dof;
};

struct EkfResult {
  bool usable = false;
  std::string failure;  // why not usable (with the time)
  double failure_time = 0;

  // Every parameter, the estimates written back; `estimated` as used (d is
  // not estimated when the scale anchor held it).
  ParameterSet parameters;
  // The free (augmented) parameters in filter order.
  std::vector<std::string> free_names;
  std::vector<int> free_indices;
  Eigen::VectorXd scales;
  Eigen::VectorXd estimate, estimate_std;  // physical units
  Eigen::MatrixXd covariance;              // final (covariance pass), scaled coordinates
  Eigen::MatrixXd prior_covariance;        // scaled
  Eigen::VectorXd filter_std;              // pass 1's own final std (physical), for comparison
  bool covariance_pass = false;
  std::string estimates_from;              // in words, for the report

  // Identifiability: the scale (ident/scale_gauge.h; gauge.held is "d" when
  // it held d) and the undetermined directions (ekf/identifiability.h).
  ScaleGauge gauge;
  std::vector<UndeterminedDirection> undetermined;
  std::vector<bool> identifiable;  // per free parameter
  std::vector<ScaleFreeRatio> ratios;

  std::vector<EkfLogHistory> logs;
  std::vector<NisStatistic> channel_nis;  // pass 1, after the burn-in
  NisStatistic total_nis;
  // Per free parameter: the time (from the start of its log chain) after
  // which the filtered estimate stays within 3 final std of its final value.
  std::vector<double> settled_after_s;
  long clamped = 0;  // projections onto bounds
  // Samples the innovation gate rejected in the estimation pass, per channel
  // (channels with none are absent).
  std::map<std::string, long> rejected;
  // Measurement noise std given, and used in the final passes (differs with
  // noise_adaptations > 0).
  NoiseWeights noise_initial, noise;
  // Log-likelihood of pass 1's innovations (prediction-error form, every
  // update): -1/2 sum_k (nu_k^T S_k^-1 nu_k + log det S_k + m_k log 2 pi).
  double log_likelihood = 0;
  // Refinement (header comment): Gauss-Newton steps taken; the largest
  // parameter step (in its own std) from pass 1's estimate, and from the
  // reported one (below refine_tolerance_std: converged); the frozen passes'
  // log-likelihood at pass 1's estimate and at the reported one.
  int refinements = 0;
  double step_std_at_pass1 = 0, step_std_at_estimate = 0;
  double frozen_log_likelihood_at_pass1 = 0, frozen_log_likelihood = 0;
  // false: stopped by max_refinements, or by a step above
  // unconverged_step_std that does not raise the likelihood
  bool refinement_converged = true;
  std::string refinement_stop;       // why it stopped, in words
  // Not converged: the parameters a further step would move by more than the
  // tolerance, with the move in std ("k_b +5.5 std, d_u -4.2 std").
  std::string short_of_maximum;
  std::vector<std::string> notes;

  // Effort (summed over passes).
  long rows = 0, updates = 0;  // per pass
  double propagation_s = 0, update_s = 0, smoother_s = 0, total_s = 0;
  double estimation_pass_s = 0, covariance_pass_s = 0;
  EkfPropagator::Counters propagation;
  Integrator::Stats integrator;
};

class EkfHistorySink;  // ekf/history_sink.h

// Runs the filter (and smoother) over flight logs in order. vehicle: model
// and parameters (values = initial estimates, `estimated` = which are
// augmented). noise: measurement noise std of every channel the logs hold.
// history: where the per-row records go (null: EkfResult::logs; otherwise
// logs stays empty). Throws InputError if options are invalid, a log is not
// a flight log, or a channel has no noise level; numerical failures give
// usable = false.
EkfResult RunEkf(const Vehicle& vehicle, const std::vector<EstimationLog>& logs,
                 const NoiseWeights& noise, const EkfOptions& options,
                 EkfHistorySink* history = nullptr);

}  // namespace coaxid
