#include "geometry/render/output_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vox {

GridGeometry outputGridGeometry(const GridGeometry& source, const std::vector<Eigen::Vector3d>& deformedPositions) {
  GridGeometry out = source;
  if (deformedPositions.empty()) {
    out.dims = {0, 0, 0};
    return out;
  }
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& p : deformedPositions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  for (int a = 0; a < 3; ++a) {
    // Lattice points (centres) inside [lo, hi], a closed interval.
    const double first = std::ceil((lo[a] - source.origin[a]) / source.spacing[a]);
    const double last = std::floor((hi[a] - source.origin[a]) / source.spacing[a]);
    out.origin[a] = source.origin[a] + source.spacing[a] * first;
    out.dims[a] = std::max<std::int64_t>(0, std::int64_t(last - first) + 1);
  }
  return out;
}

}  // namespace vox
