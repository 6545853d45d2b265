#pragma once
// A minimal parallel loop for the CPU reference kernels (slabs, rows, sample
// ranges). Items are handed out dynamically, so uneven items balance.

#include <cstdint>
#include <functional>

namespace vox {

// Threads to use for `requested` (0 or less: every hardware thread).
int workerThreads(int requested);

// Calls fn(i) for every i in [0, count) from up to workerThreads(threads)
// threads. The first exception thrown by fn is rethrown after all threads
// stop; remaining items are skipped.
void parallelFor(std::int64_t count, int threads, const std::function<void(std::int64_t)>& fn);

}  // namespace vox
