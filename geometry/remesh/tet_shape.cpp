#include "geometry/remesh/tet_shape.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace vox::remesh {

double volumeLengthQuality(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                           const Eigen::Vector3d& d) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ad = d - a;
  const double volume = ab.cross(ac).dot(ad) / 6.0;
  const double sumSq = ab.squaredNorm() + ac.squaredNorm() + ad.squaredNorm() + (c - b).squaredNorm() +
                       (d - b).squaredNorm() + (d - c).squaredNorm();
  if (!(sumSq > 0.0)) return -1.0;
  const double rms = std::sqrt(sumSq / 6.0);
  return 6.0 * std::sqrt(2.0) * volume / (rms * rms * rms);
}

double minDihedralCosine(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                         const Eigen::Vector3d& d) {
  // Outward face normals of a positive tet, face k opposite vertex k (the
  // orientation of tetFace). The interior angle between faces k and l is
  // pi minus the angle between their outward normals.
  const Eigen::Vector3d n[4] = {(c - b).cross(d - b), (d - a).cross(c - a), (b - a).cross(d - a), (c - a).cross(b - a)};
  double len[4];
  for (int k = 0; k < 4; ++k) {
    len[k] = n[k].norm();
    if (!(len[k] > 0.0)) return 1.0;
  }
  double worst = -1.0;
  for (int k = 0; k < 4; ++k)
    for (int l = k + 1; l < 4; ++l) worst = std::max(worst, -n[k].dot(n[l]) / (len[k] * len[l]));
  return std::min(worst, 1.0);
}

double minDihedralDegrees(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                          const Eigen::Vector3d& d) {
  return std::acos(std::clamp(minDihedralCosine(a, b, c, d), -1.0, 1.0)) * 180.0 / M_PI;
}

}  // namespace vox::remesh
