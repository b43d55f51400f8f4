// The pool of threads lent between fits side by side (spare_threads.h).
#include "ident/output_error/spare_threads.h"

#include <atomic>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace coaxid {
namespace {

TEST(SpareThreads, LendsWhatIsIdleAndNoMore) {
  SpareThreads pool;
  EXPECT_EQ(pool.Borrow(3), 0);  // nothing added yet
  pool.Add(2);
  EXPECT_EQ(pool.Borrow(3), 2);  // all that is idle
  EXPECT_EQ(pool.Borrow(1), 0);
  pool.Return(2);
  EXPECT_EQ(pool.Borrow(1), 1);
  EXPECT_EQ(pool.Borrow(0), 0);
  EXPECT_EQ(pool.idle(), 1);
  EXPECT_EQ(pool.lent(), 3);
}

// Borrowers racing for the pool never hold more threads at once than were
// added, and every thread comes back.
TEST(SpareThreads, ConcurrentBorrowersNeverHoldMoreThanWasAdded) {
  SpareThreads pool;
  const int added = 3;
  pool.Add(added);
  std::atomic<int> held{0}, most_held{0};
  std::atomic<long> borrowed{0};
  auto borrower = [&](int at_most) {
    for (int i = 0; i < 20000; ++i) {
      const int got = pool.Borrow(at_most);
      if (got == 0) continue;
      borrowed += got;
      const int now = held += got;
      int most = most_held.load();
      while (now > most && !most_held.compare_exchange_weak(most, now)) {
      }
      held -= got;
      pool.Return(got);
    }
  };
  std::vector<std::thread> threads;
  for (int t = 0; t < 6; ++t) threads.emplace_back(borrower, 1 + t % 3);
  for (std::thread& t : threads) t.join();
  EXPECT_LE(most_held.load(), added);
  EXPECT_GT(borrowed.load(), 0);
  EXPECT_EQ(pool.lent(), borrowed.load());
  EXPECT_EQ(pool.idle(), added);
}

}  // namespace
}  // namespace coaxid
