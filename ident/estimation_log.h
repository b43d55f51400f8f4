// A log prepared for the nonlinear estimators (output-error, EKF, the closing
// loop): its inputs as the shared zero-order hold and its output channels as
// a matrix with NaN for missing values, whatever columns the log has.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/input_hold.h"
#include "core/log.h"

namespace coaxid {

struct EstimationLog {
  std::string source;  // file, with the row range if a part: "f.csv rows 1-9600"
  std::string name;    // file stem (for output file names)
  LogKind kind = LogKind::kFlight;
  int first_log_row = 0;
  // Each row is the mean of this many consecutive rows of the log
  // (ident/fit_rate.h: AverageRows); 1 for a log read as it is.
  int log_rows_per_row = 1;
  InputHold inputs;  // t and the four inputs of every row
  // Output channels present: FlightChannel or BalanceChannel indices
  // (dynamics/outputs.h), their column names, and values (rows x channels).
  std::vector<int> channels;
  std::vector<std::string> channel_names;
  Eigen::MatrixXd values;

  int NumRows() const { return inputs.size(); }
  // The log's row (0-based) where row `row` starts, for messages.
  int LogRow(int row) const { return first_log_row + log_rows_per_row * row; }
  int NumChannels() const { return static_cast<int>(channels.size()); }
  // The median time between consecutive rows [s] (at least two rows).
  double MedianRowSpacing() const;
  // Column of `channel` in values, or -1.
  int ChannelColumn(int channel) const;
};

// How far back a log cut from a longer one keeps the source's inputs, for
// where lagged inputs stand at its first row: 10 s, ten time constants of
// the slowest lag the library's bounds allow (motor_lag, 1 s; e^-10 = 5e-5).
inline constexpr double kLeadInSeconds = 10.0;

// Rows [begin_row, end_row) of a log (end_row < 0: to the end). A channel is
// kept if its column exists and holds at least one finite value; the
// source's inputs of the kLeadInSeconds before begin_row are the inputs'
// lead-in (InputHold::SetLeadIn). Throws InputError if the range is empty or
// the log has no output channel.
EstimationLog MakeEstimationLog(const Log& log, int begin_row = 0, int end_row = -1);

// Where the held-out final part of a log starts when `fraction` of it is held
// out (cli-and-reports.md: a contiguous final part). Throws InputError if the
// fraction leaves fewer than two rows on either side.
int HoldoutStart(int num_rows, double fraction, const std::string& source);

// The rows of a log up to `seconds` after its first (the whole log if shorter).
EstimationLog FirstSecondsOf(const EstimationLog& log, double seconds);

}  // namespace coaxid
