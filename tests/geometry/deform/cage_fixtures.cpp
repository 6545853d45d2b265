#include "tests/geometry/deform/cage_fixtures.h"

#include "geometry/deform/solve/green_coordinates.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>

namespace vox::test {

TriMesh icosphere(int subdivisions) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriMesh m;
  m.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : m.positions) p.normalize();
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      m.positions.push_back((m.positions[std::size_t(a)] + m.positions[std::size_t(b)]).normalized());
      const int id = int(m.positions.size()) - 1;
      midpoint[key] = id;
      return id;
    };
    std::vector<Tri> next;
    for (const Tri& f : m.triangles) {
      const int a = mid(f[0], f[1]), b = mid(f[1], f[2]), c = mid(f[2], f[0]);
      next.push_back({f[0], a, c});
      next.push_back({f[1], b, a});
      next.push_back({f[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles = std::move(next);
  }
  return m;
}

TriMesh bumpyCage(int subdivisions, double radius, double bump, const Eigen::Vector3d& center) {
  TriMesh m = icosphere(subdivisions);
  for (auto& p : m.positions) {
    const Eigen::Vector3d u = p.normalized();
    p = center + radius * (1.0 + bump * std::sin(3.0 * u.x()) * std::cos(2.0 * u.z())) * u;
  }
  return m;
}

TriMesh subdividedBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3i& n) {
  TriMesh m;
  std::map<std::array<int, 3>, int> index;
  auto vertex = [&](std::array<int, 3> ijk) {
    auto [it, inserted] = index.try_emplace(ijk, int(m.positions.size()));
    if (inserted) {
      Eigen::Vector3d p;
      for (int a = 0; a < 3; ++a) p[a] = lo[a] + (hi[a] - lo[a]) * double(ijk[std::size_t(a)]) / double(n[a]);
      m.positions.push_back(p);
    }
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side) {
      for (int i = 0; i < n[u]; ++i)
        for (int j = 0; j < n[v]; ++j) {
          auto corner = [&](int di, int dj) {
            std::array<int, 3> ijk{};
            ijk[std::size_t(axis)] = side * n[axis];
            ijk[std::size_t(u)] = i + di;
            ijk[std::size_t(v)] = j + dj;
            return vertex(ijk);
          };
          int a = corner(0, 0), b = corner(1, 0), c = corner(1, 1), d = corner(0, 1);
          // (u, v, axis) is right-handed: a b c d is counter-clockwise seen
          // from +axis, the outside of the upper side.
          if (side == 0) std::swap(b, d);
          m.triangles.push_back({a, b, c});
          m.triangles.push_back({a, c, d});
        }
    }
  }
  return m;
}

TriMesh voxelShapeCage(const std::vector<Eigen::Vector3i>& cells) {
  auto occupied = [&](const Eigen::Vector3i& c) { return std::find(cells.begin(), cells.end(), c) != cells.end(); };
  TriMesh m;
  std::map<std::array<int, 3>, int> index;
  auto vertex = [&](const Eigen::Vector3i& p) {
    auto [it, inserted] = index.try_emplace({p.x(), p.y(), p.z()}, int(m.positions.size()));
    if (inserted) m.positions.push_back(p.cast<double>());
    return it->second;
  };
  for (const Eigen::Vector3i& c : cells)
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side) {
        Eigen::Vector3i step = Eigen::Vector3i::Zero();
        step[axis] = side ? 1 : -1;
        if (occupied(c + step)) continue;
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        auto corner = [&](int du, int dv) {
          Eigen::Vector3i p = c;
          p[axis] += side;
          p[u] += du;
          p[v] += dv;
          return vertex(p);
        };
        int a = corner(0, 0), b = corner(1, 0), d = corner(0, 1);
        const int cc = corner(1, 1);
        if (side == 0) std::swap(b, d);
        m.triangles.push_back({a, b, cc});
        m.triangles.push_back({a, cc, d});
      }
  return m;
}

double pointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& c) {
  // Closest point by Voronoi regions (Ericson, Real-Time Collision Detection 5.1.5).
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  const double denom = 1.0 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

std::vector<Eigen::Vector3d> randomInteriorPoints(const TriMesh& cage, int count, double clearance, std::mt19937& rng) {
  Eigen::Vector3d lo = cage.positions[0], hi = cage.positions[0];
  for (const auto& p : cage.positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3d> out;
  while (int(out.size()) < count) {
    const Eigen::Vector3d p = lo + Eigen::Vector3d(u(rng), u(rng), u(rng)).cwiseProduct(hi - lo);
    if (cageWindingNumber(cage, p) < 0.5) continue;
    double d = 1e300;
    for (const Tri& t : cage.triangles)
      d = std::min(d, pointTriangleDistance(p, cage.positions[std::size_t(t[0])], cage.positions[std::size_t(t[1])],
                                            cage.positions[std::size_t(t[2])]));
    if (d >= clearance) out.push_back(p);
  }
  return out;
}

}  // namespace vox::test
