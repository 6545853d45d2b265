#include "geometry/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <set>
#include <thread>
#include <utility>
#include <vector>

namespace vox {
namespace {

TEST(Parallel, ScopedWorkerThreadsSetsTheCountOfItsThreadAndRestoresIt) {
  const int all = workerThreads(0);
  {
    const ScopedWorkerThreads seven(7);
    EXPECT_EQ(workerThreads(0), 7);
    EXPECT_EQ(workerThreads(3), 3);  // an explicit count wins
    {
      const ScopedWorkerThreads one(0);  // at least one
      EXPECT_EQ(workerThreads(0), 1);
    }
    EXPECT_EQ(workerThreads(0), 7);
    int other = 0;
    std::thread([&] { other = workerThreads(0); }).join();
    EXPECT_EQ(other, all);  // the scope is its thread's only
  }
  EXPECT_EQ(workerThreads(0), all);
}

TEST(Parallel, RangesFollowTheScopedCount) {
  const ScopedWorkerThreads five(5);
  std::mutex mutex;
  std::set<std::pair<std::int64_t, std::int64_t>> ranges;
  parallelRanges(100, workerThreads(0), [&](std::int64_t b, std::int64_t e) {
    std::lock_guard lock(mutex);
    ranges.insert({b, e});
  }, 1);
  const std::set<std::pair<std::int64_t, std::int64_t>> expected{{0, 20}, {20, 40}, {40, 60}, {60, 80}, {80, 100}};
  EXPECT_EQ(ranges, expected);
  std::atomic<std::int64_t> sum{0};
  parallelFor(1000, 0, [&](std::int64_t i) { sum += i; });
  EXPECT_EQ(sum.load(), 999 * 1000 / 2);
}

}  // namespace
}  // namespace vox
