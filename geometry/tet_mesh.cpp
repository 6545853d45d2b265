#include "geometry/tet_mesh.h"

#include "geometry/cancellation.h"
#include "geometry/error.h"
#include "geometry/parallel.h"

#include <Eigen/Dense>
#include <algorithm>
#include <limits>

namespace vox {

void TetMesh::validate(const std::string& source) const {
  if (labels.size() != tets.size())
    throw InputError(source, "has " + std::to_string(tets.size()) + " tets but " + std::to_string(labels.size()) + " labels");
  for (std::size_t v = 0; v < positions.size(); ++v)
    if (!positions[v].allFinite()) throw InputError(source, "vertex " + std::to_string(v) + " has a non-finite coordinate");
  const auto nv = std::int64_t(positions.size());
  for (std::size_t t = 0; t < tets.size(); ++t) {
    if (t % 65536 == 0) throwIfCancelled();  // a mesh of millions of tets
    const Tet& q = tets[t];
    for (int k = 0; k < 4; ++k) {
      if (q[k] < 0 || q[k] >= nv)
        throw InputError(source, "tet " + std::to_string(t) + " references vertex " + std::to_string(q[k]) + " (mesh has " +
                                     std::to_string(nv) + " vertices)");
      for (int m = 0; m < k; ++m)
        if (q[m] == q[k]) throw InputError(source, "tet " + std::to_string(t) + " repeats vertex " + std::to_string(q[k]));
    }
  }
}

void setLabelNames(TetMesh& mesh, const std::map<std::int32_t, std::string>& names) {
  mesh.labelNames.clear();
  if (names.empty()) return;
  std::vector<std::int32_t> held(mesh.labels);
  std::sort(held.begin(), held.end());
  held.erase(std::unique(held.begin(), held.end()), held.end());
  for (const auto& [label, name] : names)
    if (std::binary_search(held.begin(), held.end(), label)) mesh.labelNames[label] = name;
}

double signedVolume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                    const Eigen::Vector3d& d) {
  return (b - a).cross(c - a).dot(d - a) / 6.0;
}

double signedVolume(const std::vector<Eigen::Vector3d>& p, const Tet& t) {
  return signedVolume(p[t[0]], p[t[1]], p[t[2]], p[t[3]]);
}

Tri tetFace(const Tet& t, int k) {
  // Opposite faces with outward orientation for a positive tet (0,1,2,3).
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  return {t[kFace[k][0]], t[kFace[k][1]], t[kFace[k][2]]};
}

VertexTets vertexTets(std::span<const Tet> tets, std::size_t vertexCount) {
  VertexTets out;
  out.start.assign(vertexCount + 1, 0);
  for (const Tet& t : tets)
    for (const std::int32_t v : t) ++out.start[std::size_t(v) + 1];
  for (std::size_t v = 0; v < vertexCount; ++v) out.start[v + 1] += out.start[v];
  out.tets.resize(std::size_t(out.start.back()));
  std::vector<std::int64_t> fill(out.start.begin(), out.start.end() - 1);
  for (std::size_t t = 0; t < tets.size(); ++t)
    for (const std::int32_t v : tets[t]) out.tets[std::size_t(fill[std::size_t(v)]++)] = std::int32_t(t);
  return out;
}

std::vector<std::array<std::int32_t, 4>> faceNeighbors(const TetMesh& mesh, const std::string& source) {
  return faceNeighbors(std::span<const Tet>(mesh.tets), source);
}

std::vector<std::array<std::int32_t, 4>> faceNeighbors(std::span<const Tet> tets, const std::string& source) {
  std::vector<std::array<std::int32_t, 4>> nb(tets.size(), {-1, -1, -1, -1});
  if (tets.empty()) return nb;
  std::int64_t lowest = 0, highest = -1;
  for (const Tet& t : tets)
    for (const std::int32_t v : t) {
      lowest = std::min<std::int64_t>(lowest, v);
      highest = std::max<std::int64_t>(highest, v);
    }
  if (lowest < 0) throw InputError(source, "a tet has a negative vertex index");
  // Face k of tet t is shared with the tets that hold its three vertices:
  // the intersection of their vertices' tet lists (each in tet order). A
  // face held by more than two tets names the third of them in tet order,
  // and the error the smallest such tet: the first met in tet order.
  const VertexTets around = vertexTets(tets, std::size_t(highest) + 1);
  std::vector<std::int32_t> overShared(tets.size(), std::numeric_limits<std::int32_t>::max());
  parallelFor(std::int64_t(tets.size()), 0, [&](std::int64_t ti) {
    const auto t = std::int32_t(ti);
    std::int32_t worst = std::numeric_limits<std::int32_t>::max();
    for (int k = 0; k < 4; ++k) {
      std::array<std::span<const std::int32_t>, 3> lists;
      for (int i = 0, n = 0; i < 4; ++i)
        if (i != k) lists[std::size_t(n++)] = around.of(tets[std::size_t(t)][std::size_t(i)]);
      std::array<std::size_t, 3> at = {0, 0, 0};
      int count = 0;
      while (at[0] < lists[0].size() && at[1] < lists[1].size() && at[2] < lists[2].size()) {
        const std::int32_t x = lists[0][at[0]], y = lists[1][at[1]], z = lists[2][at[2]];
        if (x == y && y == z) {
          if (x != t && nb[std::size_t(t)][std::size_t(k)] < 0) nb[std::size_t(t)][std::size_t(k)] = x;
          if (++count == 3) worst = std::min(worst, x);
          for (int l = 0; l < 3; ++l)
            while (at[std::size_t(l)] < lists[std::size_t(l)].size() && lists[std::size_t(l)][at[std::size_t(l)]] == x) ++at[std::size_t(l)];
          continue;
        }
        const std::int32_t top = std::max({x, y, z});
        for (int l = 0; l < 3; ++l)
          while (at[std::size_t(l)] < lists[std::size_t(l)].size() && lists[std::size_t(l)][at[std::size_t(l)]] < top) ++at[std::size_t(l)];
      }
    }
    overShared[std::size_t(t)] = worst;
  });
  const std::int32_t bad = *std::min_element(overShared.begin(), overShared.end());
  if (bad != std::numeric_limits<std::int32_t>::max())
    throw InputError(source, "a face of tet " + std::to_string(bad) + " is shared by more than two tets");
  return nb;
}

std::size_t orientPositively(TetMesh& mesh) {
  std::size_t flipped = 0;
  for (Tet& t : mesh.tets) {
    if (signedVolume(mesh.positions, t) < 0.0) {
      std::swap(t[2], t[3]);
      ++flipped;
    }
  }
  return flipped;
}

}  // namespace vox
