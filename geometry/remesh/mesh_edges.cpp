#include "geometry/remesh/mesh_edges.h"

#include <algorithm>

namespace vox::remesh {

void collectEdges(const RemeshComplex& complex,
                  const std::function<bool(std::int32_t, std::int32_t, double)>& keep,
                  std::vector<WeightedEdge>& out) {
  out.clear();
  std::vector<std::int32_t> star, ring;
  const std::int32_t dummy = complex.dummyVertex();
  for (std::int32_t a = 0; a < complex.vertexSlots(); ++a) {
    if (a == dummy || !complex.vertexAlive(a)) continue;
    complex.incidentTets(a, star);
    ring.clear();
    for (std::int32_t t : star)
      for (std::int32_t b : complex.tet(t))
        if (b > a && b != dummy) ring.push_back(b);
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    const Eigen::Vector3d& pa = complex.position(a);
    for (std::int32_t b : ring) {
      const double l2 = (complex.position(b) - pa).squaredNorm();
      if (keep(a, b, l2)) out.push_back({a, b, l2});
    }
  }
}

}  // namespace vox::remesh
