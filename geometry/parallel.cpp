#include "geometry/parallel.h"

#include "geometry/cancellation.h"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include <sched.h>

namespace vox {

namespace {

thread_local bool tInsideLoop = false;
thread_local int tWorkerThreads = 0;  // ScopedWorkerThreads' count (0: none)

// Runs task(k) for k in [0, parts) on the caller and up to parts - 1
// workers. Workers are created on demand and kept until exit.
class WorkerPool {
public:
  ~WorkerPool() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : workers_) t.join();
  }

  // False when another thread's loop holds the pool (the caller then runs
  // the loop alone).
  bool tryRun(int parts, const std::function<void(int)>& task) {
    std::unique_lock busy(busy_, std::try_to_lock);
    if (!busy.owns_lock()) return false;
    {
      std::lock_guard lock(mutex_);
      while (int(workers_.size()) < parts - 1) {
        const int index = int(workers_.size()) + 1;
        workers_.emplace_back([this, index] { work(index); });
      }
      task_ = &task;
      parts_ = parts;
      pending_ = parts - 1;
      ++generation_;
    }
    wake_.notify_all();
    tInsideLoop = true;
    task(0);
    tInsideLoop = false;
    std::unique_lock lock(mutex_);
    done_.wait(lock, [this] { return pending_ == 0; });
    task_ = nullptr;
    return true;
  }

private:
  void work(int index) {
    tInsideLoop = true;
    std::uint64_t seen = 0;
    for (;;) {
      const std::function<void(int)>* task = nullptr;
      {
        std::unique_lock lock(mutex_);
        wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
        if (stop_) return;
        seen = generation_;
        if (index >= parts_) continue;
        task = task_;
      }
      (*task)(index);
      {
        std::lock_guard lock(mutex_);
        --pending_;
      }
      done_.notify_one();
    }
  }

  std::mutex busy_;  // held by the thread whose loop runs
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  std::vector<std::thread> workers_;
  const std::function<void(int)>* task_ = nullptr;
  int parts_ = 0, pending_ = 0;
  std::uint64_t generation_ = 0;
  bool stop_ = false;
};

WorkerPool& pool() {
  static WorkerPool p;
  return p;
}

// Runs part(k) for k in [0, parts), on the pool when it is free, else on the
// caller; rethrows the first exception.
void runParts(int parts, const std::function<void(int)>& part, std::atomic<bool>& failed) {
  std::exception_ptr error;
  std::mutex errorMutex;
  // The workers stop where the caller would (a ScopedCancellation's flag).
  std::atomic<bool>& stop = cancellationFlag();
  const std::function<void(int)> guarded = [&](int k) {
    const ScopedCancellation scope(stop);
    try {
      part(k);
    } catch (...) {
      std::lock_guard lock(errorMutex);
      if (!error) error = std::current_exception();
      failed = true;
    }
  };
  if (parts <= 1 || tInsideLoop || !pool().tryRun(parts, guarded))
    for (int k = 0; k < parts && !failed; ++k) guarded(k);
  if (error) std::rethrow_exception(error);
}

}  // namespace

ScopedWorkerThreads::ScopedWorkerThreads(int threads) : outer_(tWorkerThreads) { tWorkerThreads = std::max(1, threads); }

ScopedWorkerThreads::~ScopedWorkerThreads() { tWorkerThreads = outer_; }

int workerThreads(int requested) {
  if (requested > 0) return requested;
  if (tWorkerThreads > 0) return tWorkerThreads;
  // The CPUs this process may run on: a batch job's allocation (Slurm's
  // cpuset) or taskset's mask, not every CPU of the node.
  cpu_set_t mask;
  if (::sched_getaffinity(0, sizeof mask, &mask) == 0 && CPU_COUNT(&mask) > 0) return CPU_COUNT(&mask);
  return std::max(1, int(std::thread::hardware_concurrency()));
}

void parallelFor(std::int64_t count, int threads, const std::function<void(std::int64_t)>& fn) {
  if (count <= 0) return;
  const int n = int(std::min<std::int64_t>(workerThreads(threads), count));
  std::atomic<std::int64_t> next{0};
  std::atomic<bool> failed{false};
  runParts(
      n,
      [&](int) {
        // Each item is a point where cancelled work stops (cancellation.h).
        for (std::int64_t i = next++; i < count && !failed; i = next++) {
          throwIfCancelled();
          fn(i);
        }
      },
      failed);
}

void parallelRanges(std::int64_t n, int threads, const std::function<void(std::int64_t, std::int64_t)>& body, std::int64_t grain) {
  if (n <= 0) {
    body(0, 0);
    return;
  }
  const std::int64_t useful = (n + grain - 1) / std::max<std::int64_t>(1, grain);
  const int k = int(std::max<std::int64_t>(1, std::min<std::int64_t>(threads, useful)));
  std::atomic<bool> failed{false};
  runParts(
      k,
      [&](int i) {
        throwIfCancelled();
        body(n * i / k, n * (i + 1) / k);
      },
      failed);
}

}  // namespace vox
