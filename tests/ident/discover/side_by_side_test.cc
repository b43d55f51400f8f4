// Fits side by side (round_refits.h): each task once, and the threads of a
// worker out of tasks lent to the tasks still running.
#include <atomic>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "ident/discover/round_refits.h"

namespace coaxid {
namespace {

TEST(SideBySide, RunsEachTaskOnce) {
  OutputErrorOptions fit;
  fit.num_threads = 3;
  OutputErrorOptions worker;
  const int n = 7;
  const int workers = SideBySideWorkers(n, fit, &worker);
  EXPECT_EQ(workers, 3);
  EXPECT_EQ(worker.num_threads, 1);
  std::vector<std::atomic<int>> runs(n);
  for (std::atomic<int>& r : runs) r = 0;
  SideBySide(n, workers, worker, [&](int k) { ++runs[k]; });
  for (int k = 0; k < n; ++k) EXPECT_EQ(runs[k].load(), 1) << "task " << k;
}

// Two tasks on two workers: the first ends at once, so the second, still
// running, can borrow its thread.
TEST(SideBySide, AWorkerOutOfTasksLendsItsThreads) {
  OutputErrorOptions fit;
  fit.num_threads = 2;
  OutputErrorOptions worker;
  const int workers = SideBySideWorkers(2, fit, &worker);
  ASSERT_EQ(workers, 2);
  ASSERT_NE(worker.spare_threads, nullptr);
  std::atomic<int> borrowed{0};
  SideBySide(2, workers, worker, [&](int k) {
    if (k == 0) return;
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (std::chrono::steady_clock::now() < give_up) {
      if ((borrowed = worker.spare_threads->Borrow(1)) > 0) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  });
  EXPECT_EQ(borrowed.load(), 1);
}

// One worker is the caller itself, which goes on after the tasks: it lends
// nothing, and keeps the pool its own options were lent from.
TEST(SideBySide, OneWorkerLendsNothing) {
  OutputErrorOptions fit;
  fit.num_threads = 1;
  fit.spare_threads = std::make_shared<SpareThreads>();
  OutputErrorOptions worker;
  const int workers = SideBySideWorkers(4, fit, &worker);
  ASSERT_EQ(workers, 1);
  EXPECT_EQ(worker.spare_threads, fit.spare_threads);
  SideBySide(4, workers, worker, [](int) {});
  EXPECT_EQ(fit.spare_threads->idle(), 0);
}

}  // namespace
}  // namespace coaxid
