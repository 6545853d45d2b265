#include "geometry/mesh_quality.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace vox {

std::array<double, 6> dihedralAngles(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                     const Eigen::Vector3d& d) {
  const Eigen::Vector3d p[4] = {a, b, c, d};
  // Edge (i,j) is shared by the faces opposite the two other vertices k, l;
  // the dihedral angle is pi minus the angle between their outward normals.
  static constexpr int kEdges[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2}, {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};
  std::array<double, 6> out{};
  for (int e = 0; e < 6; ++e) {
    const Eigen::Vector3d& pi = p[kEdges[e][0]];
    const Eigen::Vector3d& pj = p[kEdges[e][1]];
    const Eigen::Vector3d& pk = p[kEdges[e][2]];
    const Eigen::Vector3d& pl = p[kEdges[e][3]];
    const Eigen::Vector3d axis = (pj - pi).normalized();
    // Project the two opposite vertices onto the plane orthogonal to the edge.
    Eigen::Vector3d u = pk - pi;
    u -= axis * axis.dot(u);
    Eigen::Vector3d v = pl - pi;
    v -= axis * axis.dot(v);
    const double nu = u.norm(), nv = v.norm();
    if (nu == 0.0 || nv == 0.0) {
      out[e] = 0.0;
      continue;
    }
    out[e] = std::acos(std::clamp(u.dot(v) / (nu * nv), -1.0, 1.0)) * 180.0 / M_PI;
  }
  return out;
}

TetQualitySummary summarizeTetQuality(const TetMesh& mesh) {
  TetQualitySummary s;
  const double kIdeal = std::acos(1.0 / 3.0) * 180.0 / M_PI;
  double devSum = 0.0;
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    const std::int32_t label = mesh.labels[t];
    if (label <= 0) continue;
    const Tet& q = mesh.tets[t];
    const auto& P = mesh.positions;
    const double vol = signedVolume(P, q);
    ++s.tets;
    ++s.tetsPerLabel[label];
    s.volumePerLabel[label] += vol;
    if (vol <= 0.0) ++s.inverted;
    const auto ang = dihedralAngles(P[q[0]], P[q[1]], P[q[2]], P[q[3]]);
    const double lo = *std::min_element(ang.begin(), ang.end());
    const double hi = *std::max_element(ang.begin(), ang.end());
    s.minDihedral = std::min(s.minDihedral, lo);
    s.maxDihedral = std::max(s.maxDihedral, hi);
    s.under15 += lo < 15.0;
    s.under5 += lo < 5.0;
    for (double x : ang) devSum += std::abs(x - kIdeal);
  }
  if (s.tets) s.meanDeviationFrom70 = devSum / double(6 * s.tets);
  else s.minDihedral = 0.0;
  return s;
}

}  // namespace vox
