#include "geometry/raster/posed_extent.h"

#include "geometry/ascii_text.h"
#include "geometry/error.h"
#include "geometry/raster/lattice_tets.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace vox {

PosedExtent posedExtent(const GridGeometry& source, const std::vector<Eigen::Vector3d>& deformed) {
  if (deformed.empty()) throw InputError("deformed positions", "no vertices");
  for (const Eigen::Vector3d& p : deformed)
    if (!p.allFinite()) throw InputError("deformed positions", "not finite (the deformation diverged)");
  Eigen::Vector3d lo = latticeCoordinates(source, deformed[0]), hi = lo;
  for (const Eigen::Vector3d& p : deformed) {
    const Eigen::Vector3d c = latticeCoordinates(source, p);
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  // Beyond this distance a lattice index has no integer in a grid to go to,
  // and doubles no longer resolve single voxels long before.
  const double limit = double(kMaxGridVoxels);
  for (int a = 0; a < 3; ++a)
    if (!(std::abs(lo[a]) <= limit && std::abs(hi[a]) <= limit))
      throw InputError("deformed positions", "a vertex is posed " + formatNumber("%.4g", std::max(std::abs(lo[a]), std::abs(hi[a]))) +
                                                 " voxels from the source grid along axis " + std::to_string(a) +
                                                 " (more than the largest supported grid, " + std::to_string(kMaxGridVoxels) + ")");
  PosedExtent e;
  e.voxels = 1.0;
  for (int a = 0; a < 3; ++a) {
    // Voxel centres of the source lattice inside [lo, hi] (with a hair of
    // slack: centres exactly on the box may lie on a tet face).
    const double f = std::ceil(lo[a] - 1e-6), l = std::floor(hi[a] + 1e-6);
    e.first[a] = f;
    e.dims[a] = std::max(1.0, l - f + 1.0);
    e.voxels *= e.dims[a];
  }
  return e;
}

}  // namespace vox
