#include "geometry/remesh/mesh_edges.h"

#include "geometry/cancellation.h"
#include "geometry/remesh/parallel_ranges.h"

#include <algorithm>

namespace vox::remesh {

void collectEdges(const RemeshComplex& complex,
                  const std::function<bool(std::int32_t, std::int32_t, double)>& keep,
                  std::vector<WeightedEdge>& out, int threads) {
  // Vertex ranges walked in parallel, concatenated in order: the same list
  // for any thread count.
  constexpr int kChunks = 64;
  std::vector<std::vector<WeightedEdge>> chunks(kChunks);
  const std::int32_t dummy = complex.dummyVertex();
  const std::int64_t n = complex.vertexSlots();
  parallelRanges(kChunks, threads, [&](std::int64_t cb, std::int64_t ce) {
    StarWalker walker;
    std::vector<std::int32_t> star, ring;
    for (std::int64_t c = cb; c < ce; ++c)
      for (std::int32_t a = std::int32_t(n * c / kChunks); a < std::int32_t(n * (c + 1) / kChunks); ++a) {
        throwIfCancelled();
        if (a == dummy || !complex.vertexAlive(a)) continue;
        walker.incidentTets(complex, a, star);
        complex.starVertices(star, a, ring, a);
        const Eigen::Vector3d& pa = complex.position(a);
        for (std::int32_t b : ring) {
          const double l2 = (complex.position(b) - pa).squaredNorm();
          if (keep(a, b, l2)) chunks[std::size_t(c)].push_back({a, b, l2});
        }
      }
  }, 1);
  throwIfCancelled();
  std::size_t total = 0;
  for (const auto& c : chunks) total += c.size();
  out.clear();
  out.reserve(total);
  for (auto& c : chunks) {
    out.insert(out.end(), c.begin(), c.end());
    std::vector<WeightedEdge>().swap(c);  // each chunk freed once copied
  }
}

}  // namespace vox::remesh
