#include "geometry/tet_mesh.h"

#include "geometry/cancellation.h"
#include "geometry/error.h"
#include "geometry/parallel.h"

#include <Eigen/Dense>
#include <algorithm>
#include <limits>
#include <mutex>
#include <tuple>

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
  // Faces are matched within buckets by their smallest vertex: a bucket's
  // faces sorted by their other two vertices and then by tet, so that a
  // face's tets come in tet order. A face held by more than two tets names
  // the third of them, and the error the smallest such tet.
  struct Face {
    std::int32_t b, c, tet, k;  // face k is opposite vertex k
  };
  const auto vertexCount = std::size_t(highest) + 1;
  // A tet's vertices in increasing order, with their places in the tet: the
  // face opposite the smallest has the second smallest as its smallest, the
  // other three the smallest.
  const auto ordered = [&](std::size_t t) {
    std::array<std::pair<std::int32_t, std::int32_t>, 4> v;
    for (int i = 0; i < 4; ++i) v[std::size_t(i)] = {tets[t][std::size_t(i)], i};
    const auto order = [&](std::size_t i, std::size_t j) {
      if (v[j] < v[i]) std::swap(v[i], v[j]);
    };
    order(0, 1), order(2, 3), order(0, 2), order(1, 3), order(1, 2);
    return v;
  };
  std::vector<std::int64_t> start(vertexCount + 1, 0);
  for (std::size_t t = 0; t < tets.size(); ++t) {
    const auto v = ordered(t);
    start[std::size_t(v[0].first) + 1] += 3;
    start[std::size_t(v[1].first) + 1] += 1;
  }
  for (std::size_t v = 0; v < vertexCount; ++v) start[v + 1] += start[v];
  std::vector<Face> faces(4 * tets.size());
  {
    std::vector<std::int64_t> fill(start.begin(), start.end() - 1);
    for (std::size_t t = 0; t < tets.size(); ++t) {
      const auto v = ordered(t);
      const auto tet = std::int32_t(t);
      faces[std::size_t(fill[std::size_t(v[1].first)]++)] = {v[2].first, v[3].first, tet, v[0].second};
      auto& at = fill[std::size_t(v[0].first)];
      faces[std::size_t(at++)] = {v[2].first, v[3].first, tet, v[1].second};
      faces[std::size_t(at++)] = {v[1].first, v[3].first, tet, v[2].second};
      faces[std::size_t(at++)] = {v[1].first, v[2].first, tet, v[3].second};
    }
  }
  std::mutex lock;
  std::int32_t bad = std::numeric_limits<std::int32_t>::max();
  parallelRanges(std::int64_t(vertexCount), workerThreads(0), [&](std::int64_t begin, std::int64_t end) {
    std::int32_t worst = std::numeric_limits<std::int32_t>::max();
    for (auto v = std::size_t(begin); v < std::size_t(end); ++v) {
      const auto first = faces.begin() + start[v], last = faces.begin() + start[v + 1];
      std::sort(first, last, [](const Face& x, const Face& y) {
        return std::tie(x.b, x.c, x.tet, x.k) < std::tie(y.b, y.c, y.tet, y.k);
      });
      for (auto group = first; group != last;) {
        auto next = group;
        while (next != last && next->b == group->b && next->c == group->c) ++next;
        // The group's distinct tets, in tet order (a tet that repeats a
        // vertex holds the same face twice).
        std::array<std::int32_t, 3> held{};
        int count = 0;
        for (auto f = group; f != next && count < 3; ++f)
          if (count == 0 || f->tet != held[std::size_t(count - 1)]) held[std::size_t(count++)] = f->tet;
        if (count == 3) worst = std::min(worst, held[2]);
        for (auto f = group; f != next; ++f) {
          const std::int32_t other = held[0] != f->tet ? held[0] : (count > 1 ? held[1] : -1);
          nb[std::size_t(f->tet)][std::size_t(f->k)] = other;
        }
        group = next;
      }
    }
    const std::lock_guard<std::mutex> hold(lock);
    bad = std::min(bad, worst);
  });
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
