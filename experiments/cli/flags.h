// The gflags flags of `coaxid`, declared once for every subcommand.
#pragma once

#include <gflags/gflags.h>

DECLARE_string(config);
DECLARE_string(scenario);
DECLARE_string(out);
DECLARE_string(truth);
DECLARE_int64(seed);
DECLARE_string(logs);
DECLARE_string(data_dir);
DECLARE_string(method);
DECLARE_string(validate);
DECLARE_double(holdout_fraction);
DECLARE_double(process_noise);
DECLARE_string(prior);
// import (experiments/cli/import.h).
DECLARE_string(format);
DECLARE_string(in);
// identify --method=ekf (experiments/cli/identify_ekf.h).
DECLARE_bool(smoother);
DECLARE_bool(ekf_covariance_pass);
DECLARE_int32(ekf_refinements);
DECLARE_string(ekf_scale_anchor);
DECLARE_string(ekf_transition);
DECLARE_string(ekf_initial_report);
DECLARE_double(ekf_process_noise);
DECLARE_bool(ekf_process_noise_from_data);
DECLARE_double(ekf_window_s);
DECLARE_double(ekf_gate);
DECLARE_int64(ekf_noise_adaptation_rows);
DECLARE_int32(ekf_noise_adaptations);
// identify --method=kinematic (experiments/cli/identify_kinematic.h).
DECLARE_bool(kinematic_scale_factors);
DECLARE_bool(kinematic_time_offset);
DECLARE_double(kinematic_segment_s);
