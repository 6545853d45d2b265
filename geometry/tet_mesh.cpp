#include "geometry/tet_mesh.h"

#include "geometry/cancellation.h"
#include "geometry/error.h"

#include <Eigen/Dense>
#include <algorithm>
#include <unordered_map>

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

namespace {
struct FaceKey {
  std::int32_t a, b, c;
  bool operator==(const FaceKey&) const = default;
};
struct FaceKeyHash {
  std::size_t operator()(const FaceKey& k) const {
    std::uint64_t h = std::uint64_t(std::uint32_t(k.a)) * 0x9E3779B97F4A7C15ull;
    h ^= std::uint64_t(std::uint32_t(k.b)) + 0x7F4A7C159E3779B9ull + (h << 6) + (h >> 2);
    h ^= std::uint64_t(std::uint32_t(k.c)) + 0x94D049BB133111EBull + (h << 6) + (h >> 2);
    return std::size_t(h);
  }
};
FaceKey sortedKey(Tri f) {
  std::sort(f.begin(), f.end());
  return {f[0], f[1], f[2]};
}
}  // namespace

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
  std::unordered_map<FaceKey, std::int64_t, FaceKeyHash> open;  // face -> 4*tet + k
  open.reserve(tets.size() * 2);
  for (std::size_t t = 0; t < tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) {
      const FaceKey key = sortedKey(tetFace(tets[t], k));
      auto [it, inserted] = open.try_emplace(key, std::int64_t(4 * t + k));
      if (inserted) continue;
      if (it->second < 0) throw InputError(source, "a face of tet " + std::to_string(t) + " is shared by more than two tets");
      const std::int64_t other = it->second;
      nb[t][k] = std::int32_t(other / 4);
      nb[std::size_t(other / 4)][other % 4] = std::int32_t(t);
      it->second = -1;
    }
  }
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
