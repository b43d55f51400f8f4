// A full-rate simulated flight log as a real logger writes it (issue 14):
// gyros, accelerometers and attitude at the log's rate, positions at a tenth
// of it (empty fields in the other rows), and no velocities (u, v, w are
// rarely measured on a vehicle).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "core/log.h"

namespace coaxid {

inline Log MixedRateLog(const Log& full, int position_every = 10) {
  Log mixed;
  mixed.kind = full.kind;
  mixed.metadata = full.metadata;
  mixed.metadata.erase("rate_hz");
  mixed.source = full.source + " (mixed rates)";
  for (size_t c = 0; c < full.columns.size(); ++c) {
    const std::string& name = full.columns[c];
    if (name == "u" || name == "v" || name == "w") continue;
    std::vector<double> values = full.values[c];
    if (name == "x" || name == "y" || name == "z") {
      for (size_t k = 0; k < values.size(); ++k) {
        if (k % position_every != 0) values[k] = std::numeric_limits<double>::quiet_NaN();
      }
    }
    mixed.columns.push_back(name);
    mixed.values.push_back(std::move(values));
  }
  return mixed;
}

}  // namespace coaxid
