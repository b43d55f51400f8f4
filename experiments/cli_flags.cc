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
