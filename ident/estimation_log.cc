#include "ident/estimation_log.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/errors.h"
#include "dynamics/outputs.h"

namespace coaxid {

double EstimationLog::MedianRowSpacing() const {
  std::vector<double> dt;
  for (int k = 1; k < NumRows(); ++k) dt.push_back(inputs.time(k) - inputs.time(k - 1));
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  return dt[dt.size() / 2];
}

int EstimationLog::ChannelColumn(int channel) const {
  for (int c = 0; c < NumChannels(); ++c) {
    if (channels[c] == channel) return c;
  }
  return -1;
}

EstimationLog MakeEstimationLog(const Log& log, int begin_row, int end_row) {
  if (end_row < 0) end_row = log.NumRows();
  if (begin_row < 0 || end_row > log.NumRows() || end_row - begin_row < 2) {
    throw InputError(log.source + ": rows " + std::to_string(begin_row + 1) + "-" +
                     std::to_string(end_row) + " leave fewer than two samples to estimate from");
  }
  EstimationLog out;
  out.kind = log.kind;
  out.name = std::filesystem::path(log.source).stem().string();
  out.first_log_row = begin_row;
  out.source = log.source;
  if (begin_row > 0 || end_row < log.NumRows()) {
    out.source += " rows " + std::to_string(begin_row + 1) + "-" + std::to_string(end_row);
  }
  const InputHold all = InputHold::FromLog(log);
  std::vector<double> t(all.times().begin() + begin_row, all.times().begin() + end_row);
  std::vector<InputVector> u;
  for (int k = begin_row; k < end_row; ++k) u.push_back(all.input(k));
  out.inputs = InputHold(std::move(t), std::move(u));
  // Where a lagged input stands at the first row: the source's rows of the
  // kLeadInSeconds before it (dynamics/held_input.h, FirstHeldInput).
  int first = begin_row;
  while (first > 0 && all.time(first - 1) >= all.time(begin_row) - kLeadInSeconds) --first;
  std::vector<InputVector> lead_in;
  for (int k = first; k < begin_row; ++k) lead_in.push_back(all.input(k));
  out.inputs.SetLeadIn(
      std::vector<double>(all.times().begin() + first, all.times().begin() + begin_row),
      std::move(lead_in));

  const bool flight = log.kind == LogKind::kFlight;
  const int num = flight ? kNumFlightChannels : kNumBalanceChannels;
  for (int ch = 0; ch < num; ++ch) {
    const std::string name = flight ? FlightChannelName(ch) : BalanceChannelName(ch);
    if (!log.Has(name)) continue;
    const std::vector<double>& column = log.Column(name);
    bool any = false;
    for (int k = begin_row; k < end_row && !any; ++k) any = std::isfinite(column[k]);
    if (!any) continue;
    out.channels.push_back(ch);
    out.channel_names.push_back(name);
  }
  if (out.channels.empty()) {
    throw InputError(log.source + ": no output channel with data (" +
                     (flight ? "flight: x..r, ax..az" : "balance: X..N, Z1, Z2, N1, N2") + ")");
  }
  out.values.resize(end_row - begin_row, out.NumChannels());
  for (int c = 0; c < out.NumChannels(); ++c) {
    const std::vector<double>& column = log.Column(out.channel_names[c]);
    for (int k = begin_row; k < end_row; ++k) out.values(k - begin_row, c) = column[k];
  }
  return out;
}

int HoldoutStart(int num_rows, double fraction, const std::string& source) {
  if (!(fraction >= 0 && fraction < 1)) {
    throw InputError("the held-out fraction must lie in [0, 1), got " + std::to_string(fraction));
  }
  const int start = static_cast<int>(std::lround(num_rows * (1.0 - fraction)));
  if (fraction > 0 && (start < 2 || num_rows - start < 2)) {
    throw InputError(source + ": too short to hold out " + std::to_string(fraction) +
                     " of it for validation");
  }
  return start;
}

EstimationLog FirstSecondsOf(const EstimationLog& log, double seconds) {
  const std::vector<double>& t = log.inputs.times();
  const int rows = static_cast<int>(
      std::upper_bound(t.begin(), t.end(), t.front() + seconds) - t.begin());
  if (rows >= log.NumRows()) return log;
  EstimationLog part = log;
  std::vector<InputVector> inputs;
  for (int k = 0; k < rows; ++k) inputs.push_back(log.inputs.input(k));
  part.inputs = InputHold(std::vector<double>(t.begin(), t.begin() + rows), std::move(inputs));
  part.inputs.SetLeadIn(log.inputs.lead_in_times(), log.inputs.lead_in_inputs());
  part.values = log.values.topRows(rows);
  return part;
}

}  // namespace coaxid
