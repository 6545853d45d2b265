#include "geometry/parallel.h"

#include "geometry/cancellation.h"

#include <gtest/gtest.h>

#include <algorithm>
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

TEST(Parallel, AScopedCancellationStopsItsThreadAndTheLoopsItStarts) {
  std::atomic<bool> stop{false};
  const ScopedCancellation scope(stop);
  EXPECT_EQ(&cancellationFlag(), &stop);
  EXPECT_NO_THROW(throwIfCancelled());
  // Every part of a loop, on the caller or a worker, stops at the caller's flag.
  std::mutex mutex;
  std::set<std::atomic<bool>*> flags;
  const ScopedWorkerThreads four(4);
  parallelRanges(4, workerThreads(0), [&](std::int64_t, std::int64_t) {
    std::lock_guard lock(mutex);
    flags.insert(&cancellationFlag());
  }, 1);
  EXPECT_EQ(flags, std::set<std::atomic<bool>*>{&stop});
  stop = true;
  EXPECT_THROW(throwIfCancelled(), OperationCancelled);
  std::atomic<std::int64_t> done{0};
  EXPECT_THROW(parallelFor(1000, 0, [&](std::int64_t) { ++done; }), OperationCancelled);
  EXPECT_EQ(done.load(), 0);
  // Another thread, and the process, go on.
  bool otherThrew = true;
  std::atomic<bool>* otherFlag = nullptr;
  std::thread([&] {
    otherFlag = &cancellationFlag();
    try {
      throwIfCancelled();
      otherThrew = false;
    } catch (const OperationCancelled&) {
    }
  }).join();
  EXPECT_FALSE(otherThrew);
  EXPECT_EQ(otherFlag, &cancellationRequested());
  EXPECT_FALSE(cancellationRequested().load());
}

TEST(Parallel, AScopedCancellationRestoresTheOuterFlag) {
  std::atomic<bool> outer{false}, inner{true};
  {
    const ScopedCancellation a(outer);
    {
      const ScopedCancellation b(inner);
      EXPECT_THROW(throwIfCancelled(), OperationCancelled);
    }
    EXPECT_EQ(&cancellationFlag(), &outer);
    EXPECT_NO_THROW(throwIfCancelled());
  }
  EXPECT_EQ(&cancellationFlag(), &cancellationRequested());
}

// A sort of millions of items stops within its 65536 comparisons once
// stopped; not stopped, it orders as std::sort does with the same comparator.
TEST(Parallel, ASortOfAWholeMeshPollsTheCancellation) {
  std::vector<std::pair<int, int>> items(1 << 20);
  for (std::size_t i = 0; i < items.size(); ++i) items[i] = {int((i * 7919u) % 1009u), int(i % 3u)};
  auto byFirst = [](const auto& a, const auto& b) { return a.first < b.first; };  // ties: the order std::sort leaves
  std::vector<std::pair<int, int>> expected = items, sorted = items;
  std::sort(expected.begin(), expected.end(), byFirst);
  sortCancellable(sorted.begin(), sorted.end(), byFirst);
  EXPECT_EQ(sorted, expected);

  std::atomic<bool> stop{true};
  const ScopedCancellation scope(stop);
  sorted = items;
  EXPECT_THROW(sortCancellable(sorted.begin(), sorted.end(), byFirst), OperationCancelled);
  std::vector<int> few{3, 1, 2};
  EXPECT_NO_THROW(sortCancellable(few.begin(), few.end()));  // under 65536 comparisons: no poll
  EXPECT_EQ(few, (std::vector<int>{1, 2, 3}));
}

}  // namespace
}  // namespace vox
