// Flight logs sampled faster than a fit needs, averaged down to a fit rate:
// each run of `factor` consecutive rows becomes one row. A fit's cost is per
// row (one RK4 step and its sensitivities a hold), so averaging pairs of a
// 200 Hz log halves it, while the white sensor noise of the pair averages to
// 1/sqrt(2) of its std: the rows carry about the information of the rows
// they replace for every signal well below the new Nyquist frequency.
//
// The averaged log is a log of the same vehicle (tests/ident/fit_rate_test.cc
// fits it and finds the truth it was simulated from):
//  - row j's time is the mean of its rows' times (their middle), and each
//    output is their mean, which is the output at that time to within
//    (factor^2 - 1) h^2 / 24 |y''| (h the row spacing: 3.1e-6 s^2 |y''| for
//    pairs at 200 Hz); an angle is averaged on the circle;
//  - row j's inputs are the mean of the logged zero-order-hold inputs over
//    [T_j, T_{j+1}) (log-format.md: row k's input holds on [t_k, t_{k+1})),
//    so every hold of the averaged log applies the impulse the logged inputs
//    applied over it; the last row's over an interval as long as the one
//    before it;
//  - the rows before T_0 join the inputs' lead-in (FirstHeldInput).
// The averaging window (factor rows) is at most 1 / fit_rate_hz. Measured:
// pairs of 200 Hz rows (a 10 ms window) left what `coaxid discover` adds
// unchanged on 42 flight-only logs of the confusion study; runs of four (20
// ms) added rotor_damping to all four logs tried, a damping standing in for
// the averaging's own low-pass (docs/discover_confusion.md, thirtieth
// session).
#pragma once

#include <string>
#include <vector>

#include "ident/estimation_log.h"

namespace coaxid {

// How many consecutive rows of `log` one averaged row takes at `fit_rate_hz`:
// the largest factor whose window (factor rows) is at most 1 / fit_rate_hz.
// 1 (the log as it is) for a balance log, fit_rate_hz = 0, a log not sampled
// uniformly (row spacings differing by more than 1 %), or one with a missing
// value in any output channel; `why_not` (if given) then says which.
int RowsPerFitRow(const EstimationLog& log, double fit_rate_hz, std::string* why_not = nullptr);

// The log with each run of `factor` rows averaged into one (the trailing
// rows that do not fill a run are left out). factor 1 returns the log.
// Throws InputError if fewer than two rows would remain.
EstimationLog AverageRows(const EstimationLog& log, int factor);

// A flight log at the fit rate, and what was done to it (for the reports).
struct LogAtFitRate {
  EstimationLog log;
  int rows_averaged = 1;
  double log_rate_hz = 0;  // 1 / the median row spacing
  std::string note;        // "f.csv: 200 Hz, each 2 rows averaged (100 Hz)" or why kept
};

// Every log of `logs` at `fit_rate_hz` (RowsPerFitRow, AverageRows).
std::vector<LogAtFitRate> AtFitRate(const std::vector<EstimationLog>& logs, double fit_rate_hz);

}  // namespace coaxid
