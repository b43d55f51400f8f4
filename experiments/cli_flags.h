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
