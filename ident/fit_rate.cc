#include "ident/fit_rate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/errors.h"
#include "dynamics/state.h"

namespace coaxid {
namespace {

// The mean of the zero-order-hold input over [a, b), b > a.
InputVector MeanInput(const InputHold& hold, double a, double b) {
  InputVector sum{};
  for (int k = hold.IntervalAt(a); k < hold.size(); ++k) {
    const double from = std::max(a, hold.time(k));
    const double to = k + 1 < hold.size() ? std::min(b, hold.time(k + 1)) : b;
    if (to <= from) break;
    for (int i = 0; i < kNumInputs; ++i) sum[i] += (to - from) * hold.input(k)[i];
    if (to >= b) break;
  }
  for (double& v : sum) v /= b - a;
  return sum;
}

std::string Hz(double v) {
  char b[32];
  std::snprintf(b, sizeof(b), "%.4g Hz", v);
  return b;
}

}  // namespace

int RowsPerFitRow(const EstimationLog& log, double fit_rate_hz, std::string* why_not) {
  auto keep = [&](const std::string& why) {
    if (why_not != nullptr) *why_not = why;
    return 1;
  };
  if (log.kind != LogKind::kFlight) return keep("a balance log is fitted row by row");
  if (!(fit_rate_hz > 0)) return keep("fitted at its own rate");
  if (log.NumRows() < 4) return keep("too few rows to average");
  const std::vector<double>& t = log.inputs.times();
  const double h = log.MedianRowSpacing();
  for (size_t k = 0; k + 1 < t.size(); ++k) {
    if (std::fabs((t[k + 1] - t[k]) - h) > 0.01 * h) {
      return keep("fitted at its own rate: its rows are not evenly spaced (row " +
                  std::to_string(log.LogRow(k + 1) + 1) + ")");
    }
  }
  if (!log.values.allFinite()) {
    return keep("fitted at its own rate: an output channel has missing values");
  }
  const int factor = static_cast<int>(std::floor(1.0 / (h * fit_rate_hz) + 1e-6));
  if (factor < 2) return keep("already at or below the fit rate");
  if (log.NumRows() / factor < 2) return keep("too few rows to average");
  if (why_not != nullptr) why_not->clear();
  return factor;
}

EstimationLog AverageRows(const EstimationLog& log, int factor) {
  if (factor <= 1) return log;
  const int rows = log.NumRows() / factor;
  if (rows < 2) {
    throw InputError(log.source + ": " + std::to_string(log.NumRows()) +
                     " rows leave fewer than two when averaged " + std::to_string(factor) +
                     " at a time");
  }
  const InputHold& hold = log.inputs;
  std::vector<double> times(rows);
  for (int j = 0; j < rows; ++j) {
    double sum = 0;
    for (int k = 0; k < factor; ++k) sum += hold.time(factor * j + k);
    times[j] = sum / factor;
  }
  std::vector<InputVector> inputs(rows);
  for (int j = 0; j < rows; ++j) {
    const double end = j + 1 < rows ? times[j + 1] : 2 * times[j] - times[j - 1];
    inputs[j] = MeanInput(hold, times[j], end);
  }
  EstimationLog out = log;
  out.log_rows_per_row = log.log_rows_per_row * factor;
  out.inputs = InputHold(times, std::move(inputs));
  // The lead-in: the source's, then this log's rows before the first time.
  std::vector<double> lead_t = hold.lead_in_times();
  std::vector<InputVector> lead_u = hold.lead_in_inputs();
  for (int k = 0; k < hold.size() && hold.time(k) < times[0]; ++k) {
    lead_t.push_back(hold.time(k));
    lead_u.push_back(hold.input(k));
  }
  out.inputs.SetLeadIn(std::move(lead_t), std::move(lead_u));
  out.values.resize(rows, log.NumChannels());
  for (int c = 0; c < log.NumChannels(); ++c) {
    const bool angle = log.kind == LogKind::kFlight && IsEulerAngle(log.channels[c]);
    for (int j = 0; j < rows; ++j) {
      const double first = log.values(factor * j, c);
      double sum = 0;  // of the differences from the run's first row
      for (int k = 1; k < factor; ++k) {
        const double d = log.values(factor * j + k, c) - first;
        sum += angle ? std::remainder(d, 2 * M_PI) : d;
      }
      out.values(j, c) = first + sum / factor;
    }
  }
  return out;
}

std::vector<LogAtFitRate> AtFitRate(const std::vector<EstimationLog>& logs, double fit_rate_hz) {
  std::vector<LogAtFitRate> out;
  for (const EstimationLog& log : logs) {
    LogAtFitRate a;
    std::string why_not;
    a.rows_averaged = RowsPerFitRow(log, fit_rate_hz, &why_not);
    a.log = AverageRows(log, a.rows_averaged);
    if (log.kind == LogKind::kFlight && log.NumRows() >= 2)
      a.log_rate_hz = 1.0 / log.MedianRowSpacing();
    a.note = log.kind != LogKind::kFlight
                 ? log.source + ": " + why_not
                 : log.source + ": " + Hz(a.log_rate_hz) + ", " +
                       (a.rows_averaged > 1
                            ? "each " + std::to_string(a.rows_averaged) + " rows averaged (" +
                                  Hz(a.log_rate_hz / a.rows_averaged) + ")"
                            : why_not);
    out.push_back(std::move(a));
  }
  return out;
}

}  // namespace coaxid
