#include "experiments/cli_flags.h"

DEFINE_string(config, "", "vehicle config (YAML), e.g. configs/glmav.yaml");
DEFINE_string(scenario, "",
              "scenario file (YAML) or a built-in name: balance, flight");
DEFINE_string(out, "", "output file (simulate) or folder (demo, identify, discover)");
DEFINE_string(truth, "", "simulate: also write the true parameters and effects here (JSON)");
DEFINE_int64(seed, -1, "simulate: noise seed (default: the scenario's)");
DEFINE_string(logs, "", "comma-separated log files (CSV, ../shared/spec/log-format.md)");
DEFINE_string(data_dir, COAXID_DEFAULT_DATA_DIR,
              "where the shipped configs/ and data/ are (demo)");
DEFINE_string(method, "",
              "identify: the estimator: linear_kf (the paper's; ekf and output_error later)");
DEFINE_string(validate, "",
              "identify: comma-separated held-out logs for validation; without it the final "
              "part of each log is held out (--holdout_fraction)");
DEFINE_double(holdout_fraction, 0.2,
              "identify: fraction of each log held out for validation when --validate is not "
              "given (cut at a hold boundary; 0: none)");
DEFINE_double(process_noise, 0.0,
              "identify --method=linear_kf: Kalman process noise, Q = q diag(scale^2) per "
              "sample (the paper: 0)");
