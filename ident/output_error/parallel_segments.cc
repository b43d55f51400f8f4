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
  const int blocks = static_cast<int>(blocks_.size());
  const int own = std::min(num_threads_, blocks);
  const int borrowed = spare_ ? spare_->Borrow(blocks - own) : 0;
  const int workers = own + borrowed;
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
  if (borrowed > 0) spare_->Return(borrowed);
}

}  // namespace coaxid
