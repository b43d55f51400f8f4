#include "ident/baseline/balance_holds.h"

#include <glog/logging.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "core/errors.h"

namespace coaxid {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string SourceName(const Log& log) { return log.source.empty() ? "<log>" : log.source; }

std::string Stem(const std::string& path) {
  const size_t slash = path.rfind('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  const size_t dot = name.rfind('.');
  if (dot != std::string::npos && dot > 0) name = name.substr(0, dot);
  return name.empty() ? "log" : name;
}

bool SteadyPoints(const Log& log) {
  const auto it = log.metadata.find("layout");
  return it != log.metadata.end() && it->second == "steady_points";
}

// Row starts of the holds of rows [begin, end): consecutive identical inputs.
std::vector<int> HoldStarts(const std::vector<InputVector>& inputs, bool steady_points) {
  std::vector<int> starts;
  for (int k = 0; k < static_cast<int>(inputs.size()); ++k) {
    if (k == 0 || steady_points || inputs[k] != inputs[k - 1]) starts.push_back(k);
  }
  return starts;
}

std::vector<InputVector> ReadInputs(const Log& log, int begin, int end) {
  const std::string source = SourceName(log);
  std::vector<const std::vector<double>*> columns;
  for (const std::string& name : InputColumns()) {
    if (!log.Has(name)) throw InputError(source + ": column '" + name + "': missing");
    columns.push_back(&log.Column(name));
  }
  std::vector<InputVector> inputs(end - begin);
  for (int k = begin; k < end; ++k) {
    for (int i = 0; i < static_cast<int>(columns.size()); ++i) {
      const double u = (*columns[i])[k];
      if (!std::isfinite(u)) {
        throw InputError(source + ": row " + std::to_string(k + 1) + ": column '" +
                         InputColumns()[i] + "': input is not finite");
      }
      inputs[k - begin][i] = u;
    }
  }
  return inputs;
}

}  // namespace

const char* LoadChannelName(int channel) {
  static const char* const kNames[kNumLoadChannels] = {"X", "Y", "Z", "L", "M", "N"};
  CHECK(channel >= 0 && channel < kNumLoadChannels) << "load channel " << channel;
  return kNames[channel];
}

LoadVector BalanceData::RowLoads(int row) const {
  LoadVector out;
  for (int c = 0; c < kNumLoadChannels; ++c) out[c] = loads[c][row];
  return out;
}

BalanceData MakeBalanceData(const Log& log, int begin_row, int end_row) {
  const std::string source = SourceName(log);
  if (log.kind != LogKind::kBalance) {
    throw InputError(source + ": a " + std::string(LogKindName(log.kind)) +
                     " log, but the balance baseline needs balance logs (kind: balance)");
  }
  const int rows = log.NumRows();
  if (end_row < 0) end_row = rows;
  if (begin_row < 0 || end_row > rows || begin_row >= end_row) {
    throw InputError(source + ": no rows in [" + std::to_string(begin_row + 1) + ", " +
                     std::to_string(end_row) + "]");
  }
  if (!log.Has("t")) throw InputError(source + ": column 't': missing");

  BalanceData data;
  data.name = Stem(log.source);
  data.source = source;
  if (begin_row != 0 || end_row != rows) {
    data.source += " rows " + std::to_string(begin_row + 1) + "-" + std::to_string(end_row);
  }
  data.steady_points = SteadyPoints(log);
  data.first_log_row = begin_row;
  const std::vector<double>& t = log.Column("t");
  data.t.assign(t.begin() + begin_row, t.begin() + end_row);
  data.inputs = ReadInputs(log, begin_row, end_row);
  const int n = end_row - begin_row;
  for (int c = 0; c < kNumLoadChannels; ++c) {
    data.has_channel[c] = log.Has(LoadChannelName(c));
    if (data.has_channel[c]) {
      const std::vector<double>& column = log.Column(LoadChannelName(c));
      data.loads[c].assign(column.begin() + begin_row, column.begin() + end_row);
    } else {
      data.loads[c].assign(n, kNaN);
    }
  }

  const std::vector<int> starts = HoldStarts(data.inputs, data.steady_points);
  data.holds.resize(starts.size());
  for (size_t h = 0; h < starts.size(); ++h) {
    BalanceHold& hold = data.holds[h];
    hold.first_row = starts[h];
    hold.num_rows = (h + 1 < starts.size() ? starts[h + 1] : n) - starts[h];
    hold.input = data.inputs[starts[h]];
    const int stop = hold.first_row + hold.num_rows;
    for (int c = 0; c < kNumLoadChannels; ++c) {
      // Two passes: the mean, then squared deviations (no cancellation on
      // loads with a large offset).
      const std::vector<double>& z = data.loads[c];
      double sum = 0;
      int count = 0;
      for (int k = hold.first_row; k < stop; ++k) {
        if (std::isnan(z[k])) continue;
        sum += z[k];
        ++count;
      }
      hold.count[c] = count;
      hold.mean[c] = count > 0 ? sum / count : kNaN;
      double squares = 0;
      for (int k = hold.first_row; k < stop && count > 0; ++k) {
        if (std::isnan(z[k])) continue;
        squares += (z[k] - hold.mean[c]) * (z[k] - hold.mean[c]);
      }
      hold.sum_squares[c] = squares;
    }
  }
  return data;
}

int HoldoutStartRow(const Log& log, double fraction) {
  const std::string source = SourceName(log);
  if (!(fraction >= 0 && fraction < 1)) {
    throw InputError("--holdout_fraction must lie in [0, 1), got " + std::to_string(fraction));
  }
  const int rows = log.NumRows();
  if (fraction == 0) return rows;
  const std::vector<int> starts = HoldStarts(ReadInputs(log, 0, rows), SteadyPoints(log));
  if (starts.size() < 2) {
    throw InputError(source +
                     ": a single constant-input hold: nothing can be held out for "
                     "validation without splitting it (give --validate=LOGS or "
                     "--holdout_fraction=0)");
  }
  const double target = (1 - fraction) * rows;
  int best = starts[1];
  for (size_t h = 1; h < starts.size(); ++h) {
    if (std::fabs(starts[h] - target) < std::fabs(best - target)) best = starts[h];
  }
  return best;
}

}  // namespace coaxid
