// Flight-path reconstruction (issue 14; the data-compatibility check that
// Jategaonkar's "Flight Vehicle System Identification" ch. 10 and SIDPAC run
// before any aerodynamic fit): the kinematic equations alone (eqs. 34-39, and
// 40-42 with the measured specific force in place of the model's forces),
// driven by the measured rates and accelerations, must reproduce the
// measured positions, velocities and attitude. Their misfit measures the
// sensors' errors:
//   rate gyro:      p_m = (1 + s_p) p + b_p            (q, r alike)
//   accelerometer:  ax_m = (1 + s_ax) ax + b_ax        (ay, az alike)
//   time offset:    positions, velocities and attitude lag the IMU by tau:
//                   y_m(t) = y(t - tau)
// No aerodynamic model and no vehicle parameter enters: the estimates hold
// whatever the vehicle.
//
// Estimation: weighted least squares over all flight logs by multiple
// shooting. Each segment of segment_s has its own 9 kinematic states
// (x, y, z, u, v, w, phi, theta, psi at its first row); within it the
// equations are integrated by RK4 from row to row with the corrected IMU
// (rates linear between rows; the accelerometer held, as the inputs it was
// measured with are: model.md, decision 7). The measured channels are weighted by their noise
// std; the continuity defects between segments by the IMU noise integrated
// over a segment (the IMU is an input with noise: a batch smoother, not a
// deterministic replay of 60 s of integrated noise). std from the
// Gauss-Newton information of all blocks (ceres::Covariance), scaled by the
// residual variance factor.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/cores.h"
#include "core/log.h"
#include "core/statistics.h"
#include "ident/estimation_log.h"
#include "ident/noise_weights.h"

namespace coaxid {

struct KinematicOptions {
  bool scale_factors = true;  // estimate the six scale factors (else held at 0)
  bool time_offset = true;    // estimate tau (else held at 0)
  // A scale factor whose std exceeds this with the others free is not fixed
  // by the logs (s_ax, s_ay in hover, where ax, ay stay near 0): it is held
  // at 0 and the fit repeated (KinematicResult::unidentified).
  double scale_factor_std_limit = 0.05;
  double segment_s = 0.5;     // multiple-shooting segment length [s]
  double gravity = 9.81;      // [m/s^2] (the config's g)
  int max_iterations = 100;
  int num_threads = NumCores();  // every core (core/cores.h)
  std::function<void(const std::string&)> progress;  // progress lines; nullptr: none
  bool IsValid(std::string* why) const;
};

// The sensor-error parameters, in this order.
const std::vector<std::string>& KinematicParameterNames();
const std::vector<std::string>& KinematicParameterUnits();

struct KinematicResult {
  std::vector<std::string> names;     // KinematicParameterNames()
  std::vector<bool> estimated;        // false: held at 0 (options, or not fixed by the logs)
  std::vector<std::string> unidentified;  // scale factors held because the logs do not fix them
  Eigen::VectorXd estimate, std;      // std 0 where held
  Eigen::MatrixXd correlation;        // of the estimated ones, in names order (held: 0)
  double residual_variance_factor = 1;  // 2 cost / (residuals - unknowns)
  NoiseWeights noise;                  // of the measured kinematic channels (and the IMU's)
  // Per measured kinematic channel: the reconstruction's fit.
  std::map<std::string, FitError> fit;
  // Reconstructed (measured-time) kinematic channels per log: rows x the
  // log's columns, NaN for the IMU channels.
  std::vector<Eigen::MatrixXd> predictions;
  int iterations = 0;
  double initial_cost = 0, final_cost = 0, seconds = 0;
  std::string termination;
  int num_segments = 0;
  double Value(const std::string& name) const;
};

// Throws InputError on logs it cannot use (not flight; an IMU value missing;
// no position, velocity or attitude channel), ComputationError if the solve
// fails.
KinematicResult ReconstructFlightPath(const std::vector<EstimationLog>& logs,
                                      const KinematicOptions& options);

// The log with its sensor errors removed: p, q, r and ax, ay, az corrected
// ((m - b) / (1 + s)), and the late channels (positions, velocities,
// attitude) moved earlier by tau (linear interpolation between their
// samples; the ends hold their last value).
Log CorrectedLog(const Log& log, const KinematicResult& r);

}  // namespace coaxid
