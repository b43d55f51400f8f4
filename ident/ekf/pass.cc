#include "ident/ekf/pass.h"

#include <glog/logging.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <memory>
#include <utility>

#include "core/cores.h"
#include "ident/ekf/rts_smoother.h"

namespace coaxid {
namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// (log, row) of the steps first, first + 1, ..., first + count of the chained
// logs, first at (log, row).
std::vector<std::pair<int, int>> StepRows(const std::vector<EstimationLog>& logs, int log, int row,
                                          long count) {
  std::vector<std::pair<int, int>> rows;
  rows.reserve(count + 1);
  rows.push_back({log, row});
  for (long j = 0; j < count; ++j) {
    if (++row == logs[log].NumRows()) {
      ++log;
      row = 0;
    }
    rows.push_back({log, row});
  }
  return rows;
}

}  // namespace

long SmootherBlockRows(long rows, long option) {
  if (option > 0) return option;
  return std::max(256L, static_cast<long>(std::ceil(std::sqrt(static_cast<double>(rows)))));
}

long SmootherRecomputedRows(long rows, long option) {
  const long block = SmootherBlockRows(rows, option);
  return (rows - 2) / block * block;  // (blocks - 1) * block
}

PassResult RunPass(const EkfProblem& pb, const Eigen::VectorXd& p_start, bool freeze, bool smooth,
                   const EkfPassRecord& rec, EkfHistorySink* history, long* rows_done,
                   long max_rows) {
  CHECK(!(smooth && max_rows > 0)) << "RunPass: a smoothed pass runs over every row";
  const EkfOptions& options = pb.options;
  const int np = pb.free.size();
  const int nx = pb.vehicle.model.NumStates();
  const int n = nx + np;
  const Eigen::VectorXd& scales = pb.free.scales();
  PassResult out;
  out.innovations = rec.innovations;
  history->BeginPass(rec);
  EkfFilter filter(pb, p_start, freeze);
  auto fail = [&]() {
    out.ok = false;
    out.failure = filter.failure();
    out.failure_time = filter.failure_time();
    return out;
  };
  std::string why;

  // Steps: the rows of the chained logs; step s > 0 is reached by the
  // transition from step s - 1 (a prediction, or a log boundary). Block b
  // holds the transitions into steps b K + 1 .. min((b + 1) K, steps - 1),
  // from the checkpoint at step b K.
  long steps = 0;
  for (const EstimationLog& log : pb.logs) steps += log.NumRows();
  const long block = SmootherBlockRows(steps, options.smoother_block_rows);
  const long blocks = (steps - 2) / block + 1;
  const long last_block_start = (blocks - 1) * block;
  std::vector<EkfFilterState> checkpoints;
  RtsSmoother smoother(n);
  if (smooth) {
    checkpoints.reserve(blocks);
    smoother.Reserve(static_cast<int>(std::min(block, steps - 1)));
  }
  auto add_transition = [&](int L, int row) {
    if (smoother.AddTransition(filter.state().z, filter.state().P, filter.Phi(),
                               filter.predicted_z(), filter.predicted_P(), &why)) {
      return true;
    }
    return filter.Fail(pb.logs[L].inputs.time(row), L, row, why);
  };

  long step = 0;
  for (size_t L = 0; L < pb.logs.size() && !(max_rows > 0 && step >= max_rows); ++L) {
    const EstimationLog& log = pb.logs[L];
    const int N = log.NumRows();
    auto record = [&](int row) {
      const int l = static_cast<int>(L);
      const Eigen::VectorXd& z = filter.state().z;
      const Eigen::MatrixXd& P = filter.state().P;
      if (rec.innovations && !filter.updated_columns().empty()) {
        history->Innovations(l, row, filter.updated_columns(), filter.innovations(),
                             filter.InnovationStd(), filter.nis(),
                             static_cast<int>(filter.updated_columns().size()));
      }
      if (rec.states) {
        history->FilteredStates(l, row, z.head(nx), P.diagonal().head(nx).cwiseMax(0.0).cwiseSqrt());
      }
      if (np == 0) return;
      const Eigen::VectorXd p_std =
          P.diagonal().tail(np).cwiseMax(0.0).cwiseSqrt().cwiseProduct(scales);
      if (rec.parameters) history->Parameters(l, row, z.tail(np).cwiseProduct(scales), p_std);
      if (rec.std_at_estimate) history->ParameterStdAtEstimate(l, row, p_std);
    };
    for (int k = 0; k < N && !(max_rows > 0 && step >= max_rows); ++k, ++step) {
      const Clock::time_point c0 = Clock::now();
      if (!filter.Predict(static_cast<int>(L), k)) return fail();
      const Clock::time_point c1 = Clock::now();
      out.propagation_s += Seconds(c0, c1);
      // The last block's store as the rows come; the earlier blocks' are recomputed.
      if (smooth && step > last_block_start && !add_transition(static_cast<int>(L), k)) {
        return fail();
      }
      const Clock::time_point c2 = Clock::now();
      out.smoother_s += Seconds(c1, c2);
      if (!filter.Update(&out)) return fail();
      out.update_s += Seconds(c2, Clock::now());
      if (smooth && step % block == 0 && step <= last_block_start) {
        checkpoints.push_back(filter.state());
      }
      record(k);
      ++*rows_done;
      if (k > 0 && options.progress && *rows_done % options.progress_every_rows == 0) {
        options.progress(*rows_done, pb.total_rows);
      }
    }
  }
  {
    const Eigen::LLT<Eigen::MatrixXd> check(filter.state().P);
    if (check.info() != Eigen::Success) {
      const EstimationLog& log = pb.logs.back();
      filter.Fail(log.inputs.times().back(), static_cast<int>(pb.logs.size()) - 1,
                  log.NumRows() - 1, "final covariance not positive definite");
      return fail();
    }
  }
  out.z = filter.state().z;
  out.P = filter.state().P;
  if (freeze) out.step = filter.state().step.tail(np);
  EkfPropagator::Counters recompute_counters;
  Integrator::Stats recompute_integrator;
  if (smooth) {
    const Clock::time_point c0 = Clock::now();
    CHECK_EQ(static_cast<long>(checkpoints.size()), blocks);
    // Every block but the last is recomputed from its checkpoint, storing its transitions,
    // and smoothed backwards from the later block's first step. The recomputations are
    // independent: `workers` filters run them side by side on their own threads, each into its
    // own store, a few blocks ahead of the backward pass on this thread (the backward pass
    // is the cheap part). The forward pass filled the last block's store.
    const int workers = std::min(NumCores(), 4);
    std::vector<std::unique_ptr<EkfFilter>> filters;
    std::vector<std::unique_ptr<RtsSmoother>> owned;
    std::vector<RtsSmoother*> stores = {&smoother};
    for (int w = 0; w < workers; ++w) {
      filters.push_back(std::make_unique<EkfFilter>(pb, p_start, freeze));
      owned.push_back(std::make_unique<RtsSmoother>(n));
      owned.back()->Reserve(static_cast<int>(std::min(block, steps - 1)));
      stores.push_back(owned.back().get());
    }
    auto block_rows = [&](long b) {
      const long first = b * block;
      const long count = std::min(first + block, steps - 1) - first;
      return StepRows(pb.logs, checkpoints[b].log, checkpoints[b].row, count);
    };
    struct Failure {
      std::string why;
      double time = 0;
    };
    // Fills *store with block b's transitions; an empty why, or why the filter failed there.
    auto recompute_block = [&](long b, EkfFilter* again, RtsSmoother* store) -> Failure {
      const std::vector<std::pair<int, int>> rows = block_rows(b);
      again->Restore(checkpoints[b]);
      store->Clear();
      std::string error;
      for (size_t j = 1; j < rows.size(); ++j) {
        const auto [L, row] = rows[j];
        bool ok = again->Predict(L, row);
        if (ok && !store->AddTransition(again->state().z, again->state().P, again->Phi(),
                                        again->predicted_z(), again->predicted_P(), &error)) {
          ok = again->Fail(pb.logs[L].inputs.time(row), L, row, error);
        }
        if (!ok || !again->Update(nullptr)) return {again->failure(), again->failure_time()};
      }
      const EkfFilterState& end = checkpoints[b + 1];
      CHECK(again->state().z == end.z && again->state().P == end.P)
          << "EKF smoother: the recomputed rows up to row " << end.row << " of log " << end.log
          << " differ from the forward pass (a filter state not in the checkpoint)";
      return {};
    };
    // Block i from the end (i = 0: the last) uses store i % (workers + 1) and, from i = 1,
    // filter i % workers.
    std::vector<std::future<Failure>> pending(workers + 1);
    auto launch = [&](long i) {
      if (i >= blocks) return;
      pending[i % (workers + 1)] =
          std::async(std::launch::async, recompute_block, blocks - 1 - i,
                     filters[i % workers].get(), stores[i % (workers + 1)]);
    };
    for (long i = 1; i <= workers; ++i) launch(i);
    // Smoothed x, P at the first step of the later block (at the end: the filtered ones).
    Eigen::VectorXd x_next = out.z;
    Eigen::MatrixXd P_next = out.P;
    for (long i = 0; i < blocks; ++i) {
      const long b = blocks - 1 - i;
      RtsSmoother* store = stores[i % (workers + 1)];
      const std::vector<std::pair<int, int>> rows = block_rows(b);
      const long count = static_cast<long>(rows.size()) - 1;
      if (i > 0) {
        const Failure failure = pending[i % (workers + 1)].get();
        if (!failure.why.empty()) {
          out.ok = false;
          out.failure = failure.why;
          out.failure_time = failure.time;
          return out;  // the futures still running finish before they are destroyed
        }
        // Its filter is free, and the store of block i - 1 (smoothed): the next block.
        launch(i + workers);
        const long before = *rows_done;
        *rows_done += count;
        if (options.progress &&
            *rows_done / options.progress_every_rows != before / options.progress_every_rows) {
          options.progress(*rows_done, pb.total_rows);
        }
      }
      CHECK_EQ(store->size(), count);
      store->Smooth(
          x_next, P_next, [&](int j, const Eigen::VectorXd& xs, const Eigen::MatrixXd& Ps) {
            if (j == count && b < blocks - 1) return;  // the later block's first step, visited
            if (j == 0) {
              x_next = xs;
              P_next = Ps;
            }
            const auto [L, row] = rows[j];
            history->SmoothedStates(L, row, xs.head(nx),
                                    Ps.diagonal().head(nx).cwiseMax(0.0).cwiseSqrt());
          });
    }
    out.smoother_s += Seconds(c0, Clock::now());
    for (const auto& again : filters) {
      recompute_counters += again->propagator().counters();
      recompute_integrator += again->propagator().integrator_stats();
    }
  }
  // The effort of every filter (the recomputation included, as the progress counts it).
  out.counters = filter.propagator().counters();
  out.counters += recompute_counters;
  out.integrator = filter.propagator().integrator_stats();
  out.integrator += recompute_integrator;
  return out;
}

}  // namespace coaxid
