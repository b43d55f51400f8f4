// The flight segments of an output-error problem evaluated side by side,
// with Ceres itself single-threaded: the same fit on every run.
//
// Ceres evaluates residual blocks on num_threads threads, each summing the
// cost and gradient of the blocks it happened to take, and its Schur
// eliminator adds into shared cells as chunks finish: the sums' order, and
// so their last bits, change from run to run. A solve far from an optimum
// amplifies them (measured, issue 13: three two-thread replays of one
// discover run ended one restart at weighted costs 5.47e6, 5.47e6 and
// 3.03e6; one-thread replays were identical). Here Ceres runs one thread,
// and before each of its evaluations this callback runs the segments' CVODE
// simulations, the expensive part, on num_threads threads: every segment's
// result is the same whichever thread computes it, and Ceres then reads
// them in its own fixed order (CompressedSegmentCost::Prepare).
#pragma once

#include <memory>
#include <vector>

#include <ceres/evaluation_callback.h>

#include "ident/output_error/compressed_segment_cost.h"
#include "ident/output_error/spare_threads.h"

namespace coaxid {

class ParallelSegmentEvaluation : public ceres::EvaluationCallback {
 public:
  // num_threads of its own, and for each evaluation whatever `spare` has
  // idle (nullptr: none).
  explicit ParallelSegmentEvaluation(int num_threads, std::shared_ptr<SpareThreads> spare = nullptr)
      : num_threads_(num_threads), spare_(std::move(spare)) {}

  // A segment's residual block and its parameter blocks, as given to Ceres
  // (they must outlive this).
  void Add(const CompressedSegmentCost* cost, std::vector<double*> parameter_blocks);

  void PrepareForEvaluation(bool evaluate_jacobians, bool new_evaluation_point) override;

 private:
  struct Block {
    const CompressedSegmentCost* cost;
    std::vector<double*> parameters;
  };
  int num_threads_;
  std::shared_ptr<SpareThreads> spare_;
  std::vector<Block> blocks_;
};

}  // namespace coaxid
