#include "geometry/deform/cage/surface_checks.h"
#include "geometry/disjoint_sets.h"

#include "geometry/error.h"
#include "geometry/io/mesh_io.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

namespace vox {

namespace {

std::uint64_t edgeKey(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

}  // namespace

SurfaceCheck checkSurfaceTopology(const TriMesh& s) {
  SurfaceCheck c;
  c.vertices = s.vertexCount();
  c.faces = s.faceCount();
  // Per undirected edge: incident faces, and the sum of +1 (a<b) / -1 (a>b)
  // over the directions the faces run it (0 for a consistently oriented pair).
  struct EdgeUse {
    std::int32_t count = 0, direction = 0, firstFace = -1;
  };
  std::unordered_map<std::uint64_t, EdgeUse> edges;
  edges.reserve(s.faceCount() * 2);
  DisjointSets faceSets(s.faceCount());
  std::vector<std::int32_t> used(s.vertexCount(), 0);
  for (std::size_t f = 0; f < s.faceCount(); ++f) {
    const Tri& t = s.triangles[f];
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = t[k], b = t[(k + 1) % 3];
      EdgeUse& e = edges[edgeKey(a, b)];
      ++e.count;
      e.direction += a < b ? 1 : -1;
      if (e.firstFace < 0) e.firstFace = std::int32_t(f);
      else faceSets.unite(std::int32_t(f), e.firstFace);
      ++used[a];
    }
    const Eigen::Vector3d& p0 = s.positions[t[0]];
    const Eigen::Vector3d n = (s.positions[t[1]] - p0).cross(s.positions[t[2]] - p0);
    if (n.squaredNorm() == 0.0) ++c.degenerateFaces;
    c.volume += p0.dot(n) / 6.0;
  }
  c.edges = edges.size();
  for (const auto& [key, e] : edges) {
    if (e.count == 1) ++c.boundaryEdges;
    else if (e.count > 2) ++c.nonManifoldEdges;
    else if (e.direction != 0) ++c.misorientedEdges;
  }
  for (const std::int32_t u : used) c.isolatedVertices += u == 0;

  // A vertex is manifold when its faces form a single fan: faces around v
  // joined through the edges they share at v.
  std::vector<std::vector<std::int32_t>> facesAt(s.vertexCount());
  for (std::size_t f = 0; f < s.faceCount(); ++f)
    for (const std::int32_t v : s.triangles[f]) facesAt[v].push_back(std::int32_t(f));
  // firstAcross[w]: the local face of v's fan that first reached w across an
  // edge (v, w), -1 where none; reset after each vertex through the faces
  // around it, so the whole pass costs the sum of the valences (linear in
  // the faces, whatever one vertex's valence).
  std::vector<std::int32_t> firstAcross(s.vertexCount(), -1);
  for (std::size_t v = 0; v < s.vertexCount(); ++v) {
    const auto& around = facesAt[v];
    if (around.size() < 2) continue;
    DisjointSets fan(around.size());
    for (std::size_t i = 0; i < around.size(); ++i)
      for (const std::int32_t w : s.triangles[around[i]]) {
        if (w == std::int32_t(v)) continue;
        if (firstAcross[w] < 0) firstAcross[w] = std::int32_t(i);
        else fan.unite(std::int32_t(i), firstAcross[w]);
      }
    std::size_t fans = 0;
    for (std::size_t i = 0; i < around.size(); ++i) fans += fan.find(std::int32_t(i)) == std::int32_t(i);
    if (fans > 1) ++c.nonManifoldVertices;
    for (const std::int32_t f : around)
      for (const std::int32_t w : s.triangles[f]) firstAcross[w] = -1;
  }

  // Components and their genus: chi = V - E + F = 2 - 2 g per closed component.
  std::unordered_map<std::int32_t, std::array<std::int64_t, 3>> perComponent;  // root -> V, E, F
  for (std::size_t f = 0; f < s.faceCount(); ++f) perComponent[faceSets.find(std::int32_t(f))][2] += 1;
  for (const auto& [key, e] : edges) perComponent[faceSets.find(e.firstFace)][1] += 1;
  for (std::size_t v = 0; v < s.vertexCount(); ++v)
    if (!facesAt[v].empty()) perComponent[faceSets.find(facesAt[v].front())][0] += 1;
  c.components = perComponent.size();
  for (const auto& [root, vef] : perComponent) c.genus += int((2 - (vef[0] - vef[1] + vef[2])) / 2);
  return c;
}

SurfaceCheck checkSurface(const TriMesh& surface) {
  SurfaceCheck c = checkSurfaceTopology(surface);
  if (c.nonManifoldEdges == 0 && c.nonManifoldVertices == 0 && c.misorientedEdges == 0)
    c.selfIntersections = countSelfIntersections(surface);
  return c;
}

void validateCage(const TriMesh& cage, const std::string& source) {
  cage.validate(source);
  if (cage.faceCount() < 4) throw InputError(source, "a cage needs at least 4 triangles, found " + std::to_string(cage.faceCount()));
  const SurfaceCheck c = checkSurfaceTopology(cage);
  const auto n = [](std::size_t k, const char* what) { return std::to_string(k) + " " + what + (k == 1 ? "" : "s"); };
  if (c.boundaryEdges) throw InputError(source, "cage is not closed: " + n(c.boundaryEdges, "boundary edge"));
  if (c.nonManifoldEdges) throw InputError(source, "cage is not a 2-manifold: " + n(c.nonManifoldEdges, "edge") + " shared by more than two triangles");
  if (c.nonManifoldVertices) throw InputError(source, "cage is not a 2-manifold: " + n(c.nonManifoldVertices, "vertex") + " where separate sheets touch");
  if (c.misorientedEdges) throw InputError(source, "cage triangles are not consistently oriented (" + n(c.misorientedEdges, "edge") + " run the same way by both triangles)");
  if (c.isolatedVertices) throw InputError(source, "cage has " + n(c.isolatedVertices, "vertex") + " used by no triangle");
  if (c.degenerateFaces) throw InputError(source, "cage has " + n(c.degenerateFaces, "degenerate triangle") + " (zero area)");
  if (!(c.volume > 0.0)) throw InputError(source, "cage is inverted: its triangles face inwards (enclosed volume " + std::to_string(c.volume) + " mm^3)");
  const std::size_t crossings = countSelfIntersections(cage);
  if (crossings) throw InputError(source, "cage intersects itself (" + n(crossings, "pair") + " of intersecting triangles)");
}

TriMesh readCage(const std::string& path) {
  TriMesh cage = readSurface(path);
  validateCage(cage, path);
  return cage;
}

// ---------------------------------------------------------------------------
// Inside test

namespace {

// Edge function of q against the directed edge (a, b) projected on (y, z),
// computed with the endpoints in index order so both faces of an edge get
// bitwise the same value, and never 0: a tie is decided as for q moved by
// (eps, eps^2), eps -> 0 (simulation of simplicity).
int edgeSide(const TriMesh& s, std::int32_t a, std::int32_t b, double qy, double qz, double& value) {
  const bool flip = a > b;
  if (flip) std::swap(a, b);
  const Eigen::Vector3d& pa = s.positions[a];
  const Eigen::Vector3d& pb = s.positions[b];
  const double dy = pb.y() - pa.y(), dz = pb.z() - pa.z();
  double w = dy * (qz - pa.z()) - dz * (qy - pa.y());
  int sign = w > 0 ? 1 : w < 0 ? -1 : (-dz > 0 ? 1 : -dz < 0 ? -1 : (dy > 0 ? 1 : dy < 0 ? -1 : 0));
  if (flip) {
    w = -w;
    sign = -sign;
  }
  value = w;
  return sign;
}

}  // namespace

SurfaceInsideTest::SurfaceInsideTest(const TriMesh& surface) : surface_(surface) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const Eigen::Vector3d& p : surface_.positions) {
    lo = lo.cwiseMin(p.tail<2>());
    hi = hi.cwiseMax(p.tail<2>());
  }
  if (surface_.triangles.empty()) return;
  // About one face per cell on average.
  const int n = std::clamp(int(std::sqrt(double(surface_.faceCount()))), 1, 1024);
  lo_ = lo;
  for (int a = 0; a < 2; ++a) {
    cells_[a] = n;
    cellSize_[a] = std::max(hi[a] - lo[a], 1e-9) / double(n);
  }
  buckets_.resize(std::size_t(n) * std::size_t(n));
  for (std::size_t f = 0; f < surface_.faceCount(); ++f) {
    Eigen::Vector2d flo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), fhi = -flo;
    for (const std::int32_t v : surface_.triangles[f]) {
      flo = flo.cwiseMin(surface_.positions[v].tail<2>());
      fhi = fhi.cwiseMax(surface_.positions[v].tail<2>());
    }
    int c0[2], c1[2];
    for (int a = 0; a < 2; ++a) {
      c0[a] = std::clamp(int(std::floor((flo[a] - lo_[a]) / cellSize_[a])), 0, n - 1);
      c1[a] = std::clamp(int(std::floor((fhi[a] - lo_[a]) / cellSize_[a])), 0, n - 1);
    }
    for (int cz = c0[1]; cz <= c1[1]; ++cz)
      for (int cy = c0[0]; cy <= c1[0]; ++cy) buckets_[std::size_t(cz) * n + cy].push_back(std::int32_t(f));
  }
}

void SurfaceInsideTest::crossings(double y, double z, std::vector<Crossing>& out) const {
  out.clear();
  if (buckets_.empty()) return;
  const int cy = int(std::floor((y - lo_[0]) / cellSize_[0]));
  const int cz = int(std::floor((z - lo_[1]) / cellSize_[1]));
  // Points on the bounding box's far edge still belong to the last cell.
  const int by = cy == cells_[0] && y <= lo_[0] + cellSize_[0] * cells_[0] ? cy - 1 : cy;
  const int bz = cz == cells_[1] && z <= lo_[1] + cellSize_[1] * cells_[1] ? cz - 1 : cz;
  if (by < 0 || bz < 0 || by >= cells_[0] || bz >= cells_[1]) return;
  for (const std::int32_t f : buckets_[std::size_t(bz) * cells_[0] + by]) {
    const Tri& t = surface_.triangles[f];
    double w[3];
    // w[k]: edge function of the edge opposite vertex k (its barycentric weight).
    const int s0 = edgeSide(surface_, t[1], t[2], y, z, w[0]);
    const int s1 = edgeSide(surface_, t[2], t[0], y, z, w[1]);
    const int s2 = edgeSide(surface_, t[0], t[1], y, z, w[2]);
    if (s0 == 0 || s0 != s1 || s1 != s2) continue;
    const double sum = w[0] + w[1] + w[2];
    double x;
    if (sum != 0.0)
      x = (w[0] * surface_.positions[t[0]].x() + w[1] * surface_.positions[t[1]].x() + w[2] * surface_.positions[t[2]].x()) / sum;
    else
      x = (surface_.positions[t[0]].x() + surface_.positions[t[1]].x() + surface_.positions[t[2]].x()) / 3.0;
    // Counter-clockwise in (y, z) means the normal's x is positive: the
    // +x ray leaves the solid there.
    out.push_back({x, -s0});
  }
}

bool SurfaceInsideTest::contains(const Eigen::Vector3d& p) const {
  std::vector<Crossing> hits;
  crossings(p.y(), p.z(), hits);
  int winding = 0;
  for (const Crossing& c : hits)
    if (c.x < p.x()) winding += c.winding;
  return winding != 0;
}

std::vector<std::uint8_t> SurfaceInsideTest::voxelMask(const GridGeometry& g) const {
  std::vector<std::uint8_t> mask(std::size_t(g.voxelCount()), 0);
  std::vector<Crossing> hits;
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j) {
      const Eigen::Vector3d row = g.voxelCenter(0, j, k);
      crossings(row.y(), row.z(), hits);
      if (hits.empty()) continue;
      std::sort(hits.begin(), hits.end(), [](const Crossing& a, const Crossing& b) { return a.x < b.x; });
      std::size_t next = 0;
      int winding = 0;
      std::uint8_t* out = mask.data() + g.index(0, j, k);
      for (std::int64_t i = 0; i < g.dims[0]; ++i) {
        const double x = g.origin.x() + g.spacing.x() * double(i);
        while (next < hits.size() && hits[next].x < x) winding += hits[next++].winding;
        out[i] = winding != 0;
      }
    }
  return mask;
}

std::int64_t countForegroundOutside(const TriMesh& surface, const LabelGrid& grid) {
  const std::vector<std::uint8_t> inside = SurfaceInsideTest(surface).voxelMask(grid.geometry());
  std::int64_t outside = 0;
  for (std::size_t v = 0; v < inside.size(); ++v) outside += grid.labels()[v] != 0 && !inside[v];
  return outside;
}

}  // namespace vox
