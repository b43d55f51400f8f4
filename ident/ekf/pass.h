// One pass of the filter (filter.h) over every log in order, and with the
// smoother its backward pass, in memory that does not grow with the logs
// (issue 15).
//
// The smoother from checkpoints (the checkpointing of reverse-mode automatic
// differentiation, Griewank 1992, with one level): instead of
// the RTS store of every step (7.2 kB a row at n = 24; 5 GB for an hour at
// 200 Hz), the forward pass keeps the whole filter state (EkfFilterState:
// z, P, the held input, the gate's and the divergence watch's counters,
// CVODE's step hint) every K rows, K = EkfOptions::smoother_block_rows (0:
// about sqrt of the rows, at least 256), and the RTS store of the last block
// only. The backward pass then goes block by block from the last: restore
// the block's checkpoint, run its K rows again through the same filter code
// (storing only that block's C_k, D_k, a_k: rts_smoother.h), and run the RTS
// recursion backward through the block from the later block's smoothed x, P.
// The recomputed rows are the forward pass's bit for bit (same code, same
// state; checked at every block's end), so the smoothed states equal the
// all-in-memory smoother's (a block of every row: no recomputation at all).
// The blocks are independent given their checkpoints: one filter per core
// (at most 4) recomputes them side by side, each into its own store, a few
// blocks ahead of the backward recursion (which is the cheap part).
// Memory O(sqrt(rows) n^2 cores), time about one more forward pass over the
// cores.
//
// Internal to ident/ekf: ekf.cc uses it.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "ident/ekf/ekf.h"
#include "ident/ekf/filter.h"
#include "ident/ekf/history_sink.h"

namespace coaxid {

struct PassResult : EkfTally {
  bool ok = true;
  std::string failure;
  double failure_time = 0;
  Eigen::VectorXd z;  // final augmented state
  Eigen::MatrixXd P;  // and covariance
  // A frozen pass: the Gauss-Newton step of the filter's likelihood from its
  // parameters (scaled; EkfFilterState::step).
  Eigen::VectorXd step;
  double propagation_s = 0, update_s = 0, smoother_s = 0;
  EkfPropagator::Counters counters;
  Integrator::Stats integrator;
};

// One pass of the filter over every log, from parameters p_start (scaled)
// with the prior covariance. freeze: keep the parameters' mean (covariance
// pass). smooth: run the RTS smoother at the end. record: what goes to
// history (and, with innovations, which statistics the pass counts).
// rows_done counts rows for the progress report. max_rows > 0: stop after that
// many rows of the chained logs (the noise-adaptation passes).
PassResult RunPass(const EkfProblem& problem, const Eigen::VectorXd& p_start, bool freeze,
                   bool smooth, const EkfPassRecord& record, EkfHistorySink* history,
                   long* rows_done, long max_rows = 0);

// The rows per smoother block: EkfOptions::smoother_block_rows, or (0) about
// sqrt(rows), at least 256.
long SmootherBlockRows(long rows, long option);
// The rows a smoothing pass over `rows` runs twice (every block but the
// last), for the progress report.
long SmootherRecomputedRows(long rows, long option);

}  // namespace coaxid
