#include "geometry/scalar_grid.h"

#include <algorithm>
#include <cmath>

namespace vox {

float ScalarGrid::sample(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d c = geometry.continuousIndex(p);
  std::int64_t i0[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    const double hi = double(geometry.dims[a] - 1);
    const double x = std::clamp(c[a], 0.0, hi);
    i0[a] = std::min<std::int64_t>(std::int64_t(std::floor(x)), std::max<std::int64_t>(geometry.dims[a] - 2, 0));
    f[a] = geometry.dims[a] > 1 ? x - double(i0[a]) : 0.0;
  }
  double v = 0.0;
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) {
        const std::int64_t i = std::min(i0[0] + dx, geometry.dims[0] - 1);
        const std::int64_t j = std::min(i0[1] + dy, geometry.dims[1] - 1);
        const std::int64_t k = std::min(i0[2] + dz, geometry.dims[2] - 1);
        const double w = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
        v += w * double(at(i, j, k));
      }
  return float(v);
}

}  // namespace vox
