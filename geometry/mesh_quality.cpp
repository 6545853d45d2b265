#include "geometry/mesh_quality.h"

#include "geometry/cancellation.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>
#include <vector>

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
    if (t % 65536 == 0) throwIfCancelled();  // a mesh of millions of tets
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

namespace {

// Faces of the domain tets with their labels: (sorted vertices, label).
struct LabeledFace {
  std::array<std::int32_t, 3> v;
  std::int32_t label;
  std::int32_t tet;
  int k;
  bool operator<(const LabeledFace& o) const { return std::tie(v, label, tet, k) < std::tie(o.v, o.label, o.tet, o.k); }
};

}  // namespace

BoundaryFacetSummary summarizeBoundaryFacets(const TetMesh& mesh) {
  std::vector<LabeledFace> faces;
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    if (mesh.labels[t] <= 0) continue;
    for (int k = 0; k < 4; ++k) {
      const Tri f = tetFace(mesh.tets[t], k);
      std::array<std::int32_t, 3> v{f[0], f[1], f[2]};
      std::sort(v.begin(), v.end());
      faces.push_back({v, mesh.labels[t], std::int32_t(t), k});
    }
  }
  sortCancellable(faces.begin(), faces.end());
  BoundaryFacetSummary s;
  double devSum = 0.0;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].v == faces[i].v) ++j;
    // A single face, or two faces of different labels, is a boundary facet.
    if (j - i == 1 || faces[i].label != faces[i + 1].label) {
      const auto& P = mesh.positions;
      const Eigen::Vector3d p[3] = {P[std::size_t(faces[i].v[0])], P[std::size_t(faces[i].v[1])],
                                    P[std::size_t(faces[i].v[2])]};
      ++s.facets;
      for (int c = 0; c < 3; ++c) {
        const Eigen::Vector3d u = p[(c + 1) % 3] - p[c], w = p[(c + 2) % 3] - p[c];
        const double nu = u.norm(), nw = w.norm();
        const double a = nu > 0 && nw > 0 ? std::acos(std::clamp(u.dot(w) / (nu * nw), -1.0, 1.0)) * 180.0 / M_PI : 0.0;
        s.minAngle = std::min(s.minAngle, a);
        s.maxAngle = std::max(s.maxAngle, a);
        devSum += std::abs(a - 60.0);
      }
    }
    i = j;
  }
  if (s.facets) s.meanDeviationFrom60 = devSum / double(3 * s.facets);
  else s.minAngle = 0.0;
  return s;
}

EdgeLengthSummary summarizeEdgeLengths(const TetMesh& mesh, double target) {
  std::vector<std::uint64_t> edges;
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    if (mesh.labels[t] <= 0) continue;
    const Tet& q = mesh.tets[t];
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const auto a = std::uint32_t(std::min(q[std::size_t(i)], q[std::size_t(j)]));
        const auto b = std::uint32_t(std::max(q[std::size_t(i)], q[std::size_t(j)]));
        edges.push_back((std::uint64_t(a) << 32) | b);
      }
  }
  sortCancellable(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  EdgeLengthSummary s;
  s.edges = edges.size();
  if (edges.empty()) return s;
  s.minLength = std::numeric_limits<double>::infinity();
  double sum = 0.0, dev = 0.0;
  for (std::uint64_t e : edges) {
    const double l = (mesh.positions[std::size_t(e >> 32)] - mesh.positions[std::size_t(e & 0xFFFFFFFFu)]).norm();
    s.minLength = std::min(s.minLength, l);
    s.maxLength = std::max(s.maxLength, l);
    sum += l;
    if (target > 0.0) dev += std::abs(l - target) / target;
  }
  s.meanLength = sum / double(edges.size());
  s.meanRelativeDeviation = dev / double(edges.size());
  return s;
}

}  // namespace vox
