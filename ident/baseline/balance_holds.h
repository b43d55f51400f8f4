// Balance logs cut into constant-input holds (the paper's sect. 3 staircase):
// the one segmentation every baseline step (thrust map, sigma map, noise
// covariance, excitation check, Kalman filter, reconstruction) and later
// estimators share.
//
// A hold is a run of consecutive rows with identical inputs (omega1, omega2,
// delta_cx, delta_cy). A log of steady operating points (`# layout:
// steady_points`, log-format.md: one averaged row per point) gives one-row
// holds even where two consecutive points happen to share their inputs. Per
// hold and load channel the data keep the sample count, the mean and the sum
// of squared deviations about it: the sufficient statistics of any least-squares
// fit whose model is constant over a hold, and of the pooled noise variance
// of eqs. 83-84.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/input_hold.h"
#include "core/log.h"

namespace coaxid {

// The six balance loads of eqs. 57-63, in body axes: forces X, Y, Z [N],
// moments L, M, N [N m].
enum LoadChannel : int { kLoadX, kLoadY, kLoadZ, kLoadL, kLoadM, kLoadN, kNumLoadChannels };
// "X", "Y", "Z", "L", "M", "N".
const char* LoadChannelName(int channel);
using LoadVector = std::array<double, kNumLoadChannels>;
using LoadCounts = std::array<int, kNumLoadChannels>;

struct BalanceHold {
  int first_row = 0;  // rows [first_row, first_row + num_rows) of its BalanceData
  int num_rows = 0;
  InputVector input{};       // omega1 [rad/s], omega2 [rad/s], delta_cx [rad], delta_cy [rad]
  LoadCounts count{};        // finite samples per channel (0 where the column is absent)
  LoadVector mean{};         // over the finite samples; NaN where count is 0
  LoadVector sum_squares{};  // sum of (value - mean)^2 over the finite samples
};

// One balance log, or a contiguous part of one (the estimation or the held-out
// rows), with its loads and holds. Absent load columns are all NaN.
struct BalanceData {
  std::string source;  // the log's file, with the row range if a part: "b.csv rows 1-17920"
  std::string name;    // file stem, for output file names
  bool steady_points = false;
  int first_log_row = 0;  // row of the log this data starts at (0-based)
  std::vector<double> t;
  std::vector<InputVector> inputs;
  std::array<std::vector<double>, kNumLoadChannels> loads;
  std::array<bool, kNumLoadChannels> has_channel{};  // column present in the log
  std::vector<BalanceHold> holds;

  int NumRows() const { return static_cast<int>(t.size()); }
  int NumHolds() const { return static_cast<int>(holds.size()); }
  // Loads of one row (NaN where missing).
  LoadVector RowLoads(int row) const;
};

// Rows [begin_row, end_row) of a balance log (end_row < 0: to the end), cut
// into holds. Throws InputError if the log is not a balance log, the range is
// empty, or an input is not finite.
BalanceData MakeBalanceData(const Log& log, int begin_row = 0, int end_row = -1);

// The first row of the held-out final part of a log when a fraction of it is
// held out for validation: the hold boundary nearest to (1 - fraction) of the
// rows, so that no hold is split between estimation and validation, kept
// within [1, rows - 1] so that both parts have rows. fraction = 0 gives rows
// (nothing held out). Throws InputError if fraction is outside [0, 1) or the
// log has a single hold (nothing can be held out without splitting it).
int HoldoutStartRow(const Log& log, double fraction);

}  // namespace coaxid
