#pragma once
// Enumeration of the edges of the complex (those not incident to the dummy
// vertex), in increasing (a, b) order.

#include "geometry/remesh/remesh_complex.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace vox::remesh {

struct WeightedEdge {
  std::int32_t a = -1, b = -1;  // a < b
  double length2 = 0.0;         // squared length
};

// Every edge (a, b), a < b, of the complex for which keep(a, b, |ab|^2)
// holds (`keep` is called from several threads).
void collectEdges(const RemeshComplex& complex,
                  const std::function<bool(std::int32_t, std::int32_t, double)>& keep,
                  std::vector<WeightedEdge>& out, int threads = 2);

}  // namespace vox::remesh
