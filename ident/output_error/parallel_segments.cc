#include "ident/output_error/parallel_segments.h"

#include <algorithm>
#include <atomic>
#include <thread>
#include <utility>

namespace coaxid {

void ParallelSegmentEvaluation::Add(const CompressedSegmentCost* cost,
                                    std::vector<double*> parameter_blocks) {
  blocks_.push_back({cost, std::move(parameter_blocks)});
}

void ParallelSegmentEvaluation::PrepareForEvaluation(bool evaluate_jacobians,
                                                     bool /*new_evaluation_point*/) {
  // Each block keeps its last point and skips one it already holds, so a
  // repeated point costs a comparison.
  const int workers = std::min<int>(num_threads_, static_cast<int>(blocks_.size()));
  if (workers < 2) return;  // Ceres evaluates them itself, in order
  std::atomic<size_t> next{0};
  auto work = [&] {
    for (size_t k = next++; k < blocks_.size(); k = next++) {
      blocks_[k].cost->Prepare(blocks_[k].parameters.data(), evaluate_jacobians);
    }
  };
  std::vector<std::thread> threads;
  for (int t = 1; t < workers; ++t) threads.emplace_back(work);
  work();
  for (std::thread& t : threads) t.join();
}

}  // namespace coaxid
