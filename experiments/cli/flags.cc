#include "experiments/cli/flags.h"

DEFINE_string(config, "", "vehicle config (YAML), e.g. configs/glmav.yaml");
DEFINE_string(scenario, "",
              "scenario file (YAML) or a built-in name: balance, flight");
DEFINE_string(out, "", "output file (simulate) or folder (demo, identify, discover)");
DEFINE_string(truth, "",
              "simulate: also write the true parameters and effects here (JSON); compare: read "
              "them from here and give each method's error in sigma units");
DEFINE_int64(seed, -1, "simulate: noise seed (default: the scenario's)");
DEFINE_string(logs, "", "comma-separated log files (CSV, ../shared/spec/log-format.md)");
DEFINE_string(data_dir, COAXID_DEFAULT_DATA_DIR,
              "where the shipped configs/ and data/ are (demo)");
DEFINE_string(method, "",
              "identify: the estimator: linear_kf (the paper's), ekf or output_error");
DEFINE_string(validate, "",
              "identify: comma-separated held-out logs for validation; without it the final "
              "part of each log is held out (--holdout_fraction)");
DEFINE_double(holdout_fraction, 0.2,
              "identify: fraction of each log held out for validation when --validate is not "
              "given (cut at a hold boundary; 0: none)");
DEFINE_double(process_noise, 0.0,
              "identify --method=linear_kf: Kalman process noise, Q = q diag(scale^2) per "
              "sample (the paper: 0)");
DEFINE_string(prior, "",
              "identify (output_error, ekf), discover: REPORT.json[:name,name...]: parameters "
              "(value and std) from another report as Gaussian priors (output_error) or initial "
              "value and covariance (ekf); without names every estimated parameter the report "
              "gives a std. A prior on d (e.g. from a balance fit) fixes the scale of flight logs");

// import (experiments/cli/import.h).
DEFINE_string(format, "", "import: the rig's file format (tmotor28)");
DEFINE_string(in, "", "import: folder holding the rig's own CSV files");

// identify --method=ekf (experiments/cli/identify_ekf.h).
DEFINE_bool(smoother, true,
            "identify --method=ekf: Rauch-Tung-Striebel smoother over the logs (smoothed states "
            "in states.csv and as the fit windows' start states)");
DEFINE_bool(ekf_covariance_pass, true,
            "identify --method=ekf: a second filter pass linearised at the estimates gives the "
            "reported std (the single pass is over-confident on weakly observable directions)");
DEFINE_int32(ekf_refinements, 10,
             "identify --method=ekf: at most this many Gauss-Newton steps of the filter's "
             "likelihood when the covariance pass finds the estimate short of its maximum "
             "(ident/ekf/ekf.h, Refinement; 0: report the single pass's estimate)");
DEFINE_string(ekf_scale_anchor, "d",
              "identify --method=ekf: d (hold d at its config value when d, gamma1, gamma2, "
              "Ixx, Iyy, Izz are all free: flight logs fix only their ratios) or none (augment "
              "all, report the undetermined direction)");
DEFINE_string(ekf_transition, "linearised",
              "identify --method=ekf: state-transition matrix from the midpoint Jacobian "
              "(linearised) or from the variational equations (sensitivities, ~8x slower)");
DEFINE_string(ekf_initial_report, "",
              "identify --method=ekf: start the free parameters from this report.json's values "
              "and std (e.g. output_error's on other data) instead of the config");
DEFINE_double(ekf_process_noise, 1.0,
              "identify --method=ekf: multiplier of the default process-noise PSDs (raise it "
              "when the NIS in the report is above its band: model error)");
DEFINE_bool(ekf_process_noise_from_data, true,
            "identify --method=ekf: before the run, probe the first 20 s of the flight logs and "
            "raise the velocity and rate process noise tenfold per pass until the filter stays "
            "consistent (ident/ekf/process_noise_from_data.h); false: exactly "
            "--ekf_process_noise");
DEFINE_double(ekf_window_s, 1.0,
              "identify --method=ekf: prediction window of the fit and validation errors [s]");
DEFINE_double(ekf_gate, 1e-6,
              "identify --method=ekf: innovation gate: a sample beyond the chi-square(1) "
              "quantile at 1 - this probability is rejected as a glitch and counted per channel "
              "in report.json (0: no gate)");
DEFINE_int64(ekf_noise_adaptation_rows, 120000,
             "identify --method=ekf: rows (from the start of the chained logs) each noise "
             "adaptation pass runs over; 0: every row. 10 minutes at 200 Hz fix each channel's "
             "noise to ~0.4 %");
DEFINE_int32(ekf_noise_adaptations, 1,
             "identify --method=ekf: re-estimate the measurement noise from the innovations "
             "and run the estimation again this many times (0: keep the first-difference "
             "estimate)");
DEFINE_bool(kinematic_scale_factors, true,
            "identify --method=kinematic: estimate the gyro and accelerometer scale factors "
            "(those the logs do not fix are held at 0 anyway)");
DEFINE_bool(kinematic_time_offset, true,
            "identify --method=kinematic: estimate the time offset of the positions, velocities "
            "and attitude behind the IMU");
DEFINE_double(kinematic_segment_s, 0.5,
              "identify --method=kinematic: multiple-shooting segment length [s]");
