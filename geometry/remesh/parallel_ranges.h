#pragma once
// Static partition of [0, n) over a few threads. Each index is handled by
// exactly one call and results go to per-index slots, so the outcome does
// not depend on scheduling. `grain`: fewest indices worth a thread.
// Unlike vox::parallelFor (geometry/parallel.h, one call per item), the body
// gets a whole range, so per-thread scratch (star walkers, candidate lists)
// is built once per thread.

#include <algorithm>
#include <cstdint>
#include <thread>
#include <vector>

namespace vox::remesh {

template <typename Body>
void parallelRanges(std::int64_t n, int threads, const Body& body, std::int64_t grain = 4096) {
  const std::int64_t useful = (n + grain - 1) / std::max<std::int64_t>(1, grain);
  threads = int(std::max<std::int64_t>(1, std::min<std::int64_t>(threads, useful)));
  if (threads == 1) {
    body(std::int64_t(0), n);
    return;
  }
  std::vector<std::thread> pool;
  for (int i = 0; i < threads; ++i) {
    const std::int64_t b = n * i / threads, e = n * (i + 1) / threads;
    pool.emplace_back([&body, b, e] { body(b, e); });
  }
  for (auto& t : pool) t.join();
}

}  // namespace vox::remesh
