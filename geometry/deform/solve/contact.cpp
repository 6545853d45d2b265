#include "geometry/deform/solve/contact.h"

#include "geometry/cell_index.h"
#include "geometry/error.h"
#include "geometry/parallel.h"
#include "geometry/tri_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace vox {
namespace {

// How far p lies inside the tet (a, b, c, d) of positive volume: the
// smallest distance to its four faces' planes, negative outside.
double depthInside(const Eigen::Vector3d& p, const std::array<Eigen::Vector3d, 4>& x) {
  const double volume = (x[1] - x[0]).cross(x[2] - x[0]).dot(x[3] - x[0]);
  if (!(volume > 0.0)) return -std::numeric_limits<double>::infinity();
  static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  double depth = std::numeric_limits<double>::infinity();
  for (const auto& f : kFace) {
    const Eigen::Vector3d n = (x[std::size_t(f[1])] - x[std::size_t(f[0])]).cross(x[std::size_t(f[2])] - x[std::size_t(f[0])]);
    const double area2 = n.norm();
    if (!(area2 > 0.0)) return -std::numeric_limits<double>::infinity();
    depth = std::min(depth, -(p - x[std::size_t(f[0])]).dot(n) / area2);  // outward normal: inside is negative
  }
  return depth;
}

// Face adjacency (faceNeighbors) of tets whose vertex indices are all below
// vertexCount; throws InputError("contact", ...) otherwise.
std::vector<std::array<std::int32_t, 4>> checkedNeighbours(std::span<const Tet> tets, std::size_t vertexCount) {
  for (std::size_t t = 0; t < tets.size(); ++t)
    for (const std::int32_t v : tets[t])
      if (v < 0 || std::size_t(v) >= vertexCount) throw InputError("contact", "tet " + std::to_string(t) + " has a vertex index out of range");
  return faceNeighbors(tets, "contact");
}

}  // namespace

std::vector<std::array<std::int32_t, 3>> boundaryFaces(std::span<const Tet> tets, std::size_t vertexCount) {
  const std::vector<std::array<std::int32_t, 4>> neighbours = checkedNeighbours(tets, vertexCount);
  std::vector<std::array<std::int32_t, 3>> out;
  for (std::size_t t = 0; t < tets.size(); ++t)
    for (int k = 0; k < 4; ++k)
      if (neighbours[t][std::size_t(k)] < 0) {
        const Tri f = tetFace(tets[t], k);
        out.push_back({f[0], f[1], f[2]});
      }
  return out;
}

std::vector<Penetration> findPenetrations(std::span<const Eigen::Vector3d> rest, std::span<const Tet> tets,
                                          std::span<const Eigen::Vector3d> positions, std::span<const std::uint8_t> candidate,
                                          std::span<const std::uint8_t> penetrable, const ContactOptions& options) {
  const std::size_t nv = rest.size();
  if (positions.size() != nv || candidate.size() != nv || penetrable.size() != tets.size() ||
      !(options.side.empty() || options.side.size() == nv))
    throw InputError("contact", "the positions, candidates, penetrable flags or sides do not match the mesh");
  if (tets.empty()) return {};
  const double apart2 = options.restSeparationMm * options.restSeparationMm;

  // The candidates on the mesh's boundary, and the penetrable tets' boundary
  // faces (a face of the mesh's boundary, or one beside a tet that is not
  // penetrable), from one adjacency.
  const std::vector<std::array<std::int32_t, 4>> neighbours = checkedNeighbours(tets, nv);
  std::vector<Tet> penetrableTets;
  std::vector<std::int32_t> penetrableIndex;
  std::vector<std::array<std::int32_t, 3>> faces;
  std::vector<std::uint8_t> onBoundary(nv, 0);
  for (std::size_t t = 0; t < tets.size(); ++t) {
    if (penetrable[t]) {
      penetrableTets.push_back(tets[t]);
      penetrableIndex.push_back(std::int32_t(t));
    }
    for (int k = 0; k < 4; ++k) {
      const std::int32_t n = neighbours[t][std::size_t(k)];
      if (n >= 0 && !(penetrable[t] && !penetrable[std::size_t(n)])) continue;
      const Tri f = tetFace(tets[t], k);
      if (n < 0)
        for (const std::int32_t v : f) onBoundary[std::size_t(v)] = 1;
      if (penetrable[t]) faces.push_back({f[0], f[1], f[2]});
    }
  }
  // Queries: the candidate boundary vertices, then (faceCentroids) the
  // centroids of the boundary faces of three candidates.
  struct Query {
    Eigen::Vector3d p;
    std::array<std::int32_t, 3> of;  // the vertex (then -1, -1), or the face's vertices
  };
  std::vector<Query> queries;
  for (std::size_t v = 0; v < nv; ++v)
    if (candidate[v] && onBoundary[v]) queries.push_back({positions[v], {std::int32_t(v), -1, -1}});
  if (options.faceCentroids)
    for (std::size_t t = 0; t < tets.size(); ++t)
      for (int k = 0; k < 4; ++k) {
        if (neighbours[t][std::size_t(k)] >= 0) continue;
        const Tri f = tetFace(tets[t], k);
        if (!candidate[std::size_t(f[0])] || !candidate[std::size_t(f[1])] || !candidate[std::size_t(f[2])]) continue;
        queries.push_back({(positions[std::size_t(f[0])] + positions[std::size_t(f[1])] + positions[std::size_t(f[2])]) / 3.0, {f[0], f[1], f[2]}});
      }
  if (queries.empty() || penetrableTets.empty()) return {};

  // Cells about the mean edge of the penetrable tets.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  double edgeSum = 0.0;
  for (const Tet& t : penetrableTets) {
    for (const std::int32_t v : t) {
      lo = lo.cwiseMin(positions[std::size_t(v)]);
      hi = hi.cwiseMax(positions[std::size_t(v)]);
    }
    edgeSum += (positions[std::size_t(t[1])] - positions[std::size_t(t[0])]).norm();
  }
  for (const Query& q : queries) {
    lo = lo.cwiseMin(q.p);
    hi = hi.cwiseMax(q.p);
  }
  const double cell = std::max({2.0 * edgeSum / double(penetrableTets.size()), (hi - lo).maxCoeff() / double(1 << 19), 1e-6});
  CellIndex tetCells(cell, lo), faceCells(cell, lo);
  const auto addBox = [&](CellIndex& cells, std::size_t item, const auto& vertices) {
    Eigen::Vector3d a = positions[std::size_t(vertices[0])], b = a;
    for (const std::int32_t v : vertices) {
      a = a.cwiseMin(positions[std::size_t(v)]);
      b = b.cwiseMax(positions[std::size_t(v)]);
    }
    cells.add(std::int32_t(item), a, b);
  };
  for (std::size_t i = 0; i < penetrableTets.size(); ++i) addBox(tetCells, i, penetrableTets[i]);
  for (std::size_t i = 0; i < faces.size(); ++i) addBox(faceCells, i, faces[i]);
  tetCells.finish();
  faceCells.finish();

  const std::span<const std::int32_t> side = options.side;
  const auto apart = [&](std::int32_t v, std::int32_t u) {
    if (!side.empty() && side[std::size_t(v)] >= 0 && side[std::size_t(u)] >= 0 && side[std::size_t(v)] != side[std::size_t(u)]) return true;
    return (rest[std::size_t(v)] - rest[std::size_t(u)]).squaredNorm() > apart2;
  };
  std::vector<std::optional<Penetration>> found(queries.size());
  parallelFor(std::int64_t(queries.size()), 0, [&](std::int64_t q) {
    const Query& query = queries[std::size_t(q)];
    const Eigen::Vector3d& p = query.p;
    const bool isVertex = query.of[1] < 0;
    const std::int32_t v = query.of[0];
    // Apart at rest from u: the vertex, or each of the face's vertices.
    const auto apartFrom = [&](std::int32_t u) {
      for (const std::int32_t w : query.of)
        if (w >= 0 && !apart(w, u)) return false;
      return true;
    };
    // A tet it lies in (closed; the first by index), apart from it at rest.
    std::int32_t inside = -1;
    tetCells.forEachIn(p, p, [&](std::int32_t i) {
      if (inside >= 0 && penetrableIndex[std::size_t(i)] >= inside) return;
      const Tet& t = penetrableTets[std::size_t(i)];
      for (const std::int32_t u : t)
        if (!apartFrom(u)) return;
      std::array<Eigen::Vector3d, 4> x;
      for (std::size_t c = 0; c < 4; ++c) x[c] = positions[std::size_t(t[c])];
      if (depthInside(p, x) >= -1e-9 * cell) inside = penetrableIndex[std::size_t(i)];
    });
    if (inside < 0) return;
    // The nearest boundary face apart from v at rest, in growing boxes.
    double best2 = std::numeric_limits<double>::infinity();
    Penetration pen;
    pen.vertex = isVertex ? v : -1;
    pen.of = query.of;
    pen.at = p;
    pen.tet = inside;
    for (double r = cell; r <= 2.0 * options.searchMm; r *= 2.0) {
      faceCells.forEachIn(p - Eigen::Vector3d::Constant(r), p + Eigen::Vector3d::Constant(r), [&](std::int32_t i) {
        const auto& f = faces[std::size_t(i)];
        if (!apartFrom(f[0]) || !apartFrom(f[1]) || !apartFrom(f[2])) return;
        const Eigen::Vector3d s =
            nearestPointOnTriangle(p, positions[std::size_t(f[0])], positions[std::size_t(f[1])], positions[std::size_t(f[2])]);
        const double d2 = (s - p).squaredNorm();
        if (d2 < best2 || (d2 == best2 && f < pen.face)) {
          best2 = d2;
          pen.surface = s;
          pen.face = f;
        }
      });
      if (best2 <= r * r) break;
    }
    if (!(best2 <= options.searchMm * options.searchMm)) return;
    pen.depth = std::sqrt(best2);
    if (pen.depth <= options.toleranceMm) return;  // on the boundary: touching
    found[std::size_t(q)] = pen;
  });
  std::vector<Penetration> out;
  for (const auto& f : found)
    if (f) out.push_back(*f);
  return out;
}

}  // namespace vox
