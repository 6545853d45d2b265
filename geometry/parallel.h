#pragma once
// The project's one parallel loop: a process-wide pool of worker threads,
// started on first use and kept, that runs the loops of the CPU kernels,
// the remesher and the deformation's per-frame products.
//
// Two shapes of loop:
//  - parallelFor: one call per item, items handed out dynamically (uneven
//    items balance);
//  - parallelRanges: a static partition of [0, n) into one range per thread
//    (per-thread scratch is built once per range, and which thread handles
//    an index never depends on scheduling).
// A loop started inside another (nested), or while another thread's loop
// holds the pool, runs on its calling thread alone: no deadlock, and the
// viewer's frame never waits for an export's loop.

#include <cstdint>
#include <functional>

namespace vox {

// Threads to use for `requested` (0 or less: every CPU the process may run
// on, as its affinity mask allows, or the count a ScopedWorkerThreads of the
// calling thread sets).
int workerThreads(int requested);

// While it lives, workerThreads(0) on the constructing thread returns
// `threads` (at least 1), more than the CPUs if asked: a stage run on one
// thread and on several must give the same bytes, and the tests that check
// it pick both counts. Scopes nest; the destructor restores the outer one.
class ScopedWorkerThreads {
public:
  explicit ScopedWorkerThreads(int threads);
  ~ScopedWorkerThreads();
  ScopedWorkerThreads(const ScopedWorkerThreads&) = delete;
  ScopedWorkerThreads& operator=(const ScopedWorkerThreads&) = delete;

private:
  int outer_;
};

// Calls fn(i) for every i in [0, count) from up to workerThreads(threads)
// threads. The first exception thrown by fn is rethrown after all threads
// stop; remaining items are skipped.
void parallelFor(std::int64_t count, int threads, const std::function<void(std::int64_t)>& fn);

// Calls body(begin, end) once per range of a static partition of [0, n) into
// min(threads, ceil(n / grain)) ranges (at least one; `threads` as given,
// not workerThreads: 0 or 1 runs serially). Range i is
// [n i / k, n (i + 1) / k). Exceptions as parallelFor.
void parallelRanges(std::int64_t n, int threads, const std::function<void(std::int64_t, std::int64_t)>& body,
                    std::int64_t grain = 4096);

}  // namespace vox
