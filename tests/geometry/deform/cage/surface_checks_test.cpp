#include "geometry/deform/cage/surface_checks.h"

#include "geometry/error.h"
#include "geometry/io/mesh_io.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

namespace vox {
namespace {

// Axis-aligned box [lo, hi], 12 triangles counter-clockwise from outside.
TriMesh box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  TriMesh m;
  for (int c = 0; c < 8; ++c) m.positions.emplace_back(c & 1 ? hi.x() : lo.x(), c & 2 ? hi.y() : lo.y(), c & 4 ? hi.z() : lo.z());
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

TriMesh append(TriMesh a, const TriMesh& b) {
  const auto offset = std::int32_t(a.positions.size());
  a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
  for (Tri t : b.triangles) a.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return a;
}

// Subdivided icosahedron projected on a sphere.
TriMesh sphere(const Eigen::Vector3d& centre, double radius, int subdivisions) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriMesh m;
  for (const auto& p : {Eigen::Vector3d(-1, t, 0), Eigen::Vector3d(1, t, 0), Eigen::Vector3d(-1, -t, 0), Eigen::Vector3d(1, -t, 0),
                        Eigen::Vector3d(0, -1, t), Eigen::Vector3d(0, 1, t), Eigen::Vector3d(0, -1, -t), Eigen::Vector3d(0, 1, -t),
                        Eigen::Vector3d(t, 0, -1), Eigen::Vector3d(t, 0, 1), Eigen::Vector3d(-t, 0, -1), Eigen::Vector3d(-t, 0, 1)})
    m.positions.push_back(p.normalized());
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    const auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto [it, inserted] = mid.try_emplace(key, int(m.positions.size()));
      if (inserted) m.positions.push_back((m.positions[a] + m.positions[b]).normalized());
      return it->second;
    };
    std::vector<Tri> next;
    for (const Tri& f : m.triangles) {
      const int a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.push_back({f[0], a, c});
      next.push_back({f[1], b, a});
      next.push_back({f[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles = next;
  }
  for (auto& p : m.positions) p = centre + radius * p;
  return m;
}

TriMesh torus(double major, double minor, int nu, int nv) {
  TriMesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
      m.positions.emplace_back((major + minor * std::cos(v)) * std::cos(u), (major + minor * std::cos(v)) * std::sin(u), minor * std::sin(v));
    }
  const auto id = [&](int i, int j) { return std::int32_t(((i + nu) % nu) * nv + (j + nv) % nv); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

std::string validationError(const TriMesh& cage) {
  try {
    validateCage(cage, "cage.obj");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(SurfaceChecks, ClosedBox) {
  const SurfaceCheck c = checkSurface(box({0, 0, 0}, {2, 3, 4}));
  EXPECT_TRUE(c.closedManifold());
  EXPECT_TRUE(c.validCage());
  EXPECT_EQ(c.components, 1u);
  EXPECT_EQ(c.genus, 0);
  EXPECT_EQ(c.edges, 18u);
  EXPECT_NEAR(c.volume, 24.0, 1e-12);
  EXPECT_EQ(validationError(box({0, 0, 0}, {1, 1, 1})), "");
}

TEST(SurfaceChecks, TorusHasGenusOne) {
  const TriMesh t = torus(3.0, 1.0, 24, 12);
  const SurfaceCheck c = checkSurface(t);
  EXPECT_TRUE(c.validCage());
  EXPECT_EQ(c.genus, 1);
  EXPECT_NEAR(c.volume, 2 * M_PI * M_PI * 3.0 * 1.0, 0.1 * 2 * M_PI * M_PI * 3.0);
}

TEST(SurfaceChecks, RejectsOpenNonManifoldInvertedAndSelfIntersectingCages) {
  TriMesh open = box({0, 0, 0}, {1, 1, 1});
  open.triangles.pop_back();
  EXPECT_EQ(checkSurfaceTopology(open).boundaryEdges, 3u);
  EXPECT_EQ(validationError(open), "cage.obj: cage is not closed: 3 boundary edges");

  TriMesh fin = box({0, 0, 0}, {1, 1, 1});
  fin.positions.emplace_back(0.5, -1.0, 0.0);
  fin.triangles.push_back({0, 1, 8});
  fin.triangles.push_back({1, 0, 8});
  EXPECT_GT(checkSurfaceTopology(fin).nonManifoldEdges, 0u);
  EXPECT_NE(validationError(fin).find("shared by more than two triangles"), std::string::npos);

  // Two boxes touching at one corner: every edge is fine, the vertex is not.
  TriMesh touching = append(box({0, 0, 0}, {1, 1, 1}), box({1, 1, 1}, {2, 2, 2}));
  for (Tri& t : touching.triangles)
    for (auto& v : t)
      if (v == 8) v = 7;
  EXPECT_EQ(checkSurfaceTopology(touching).nonManifoldVertices, 1u);
  EXPECT_NE(validationError(touching).find("where separate sheets touch"), std::string::npos);

  TriMesh flipped = box({0, 0, 0}, {1, 1, 1});
  flipped.triangles[3] = {flipped.triangles[3][0], flipped.triangles[3][2], flipped.triangles[3][1]};
  EXPECT_EQ(checkSurfaceTopology(flipped).misorientedEdges, 3u);
  EXPECT_NE(validationError(flipped).find("not consistently oriented"), std::string::npos);

  TriMesh inverted = box({0, 0, 0}, {1, 1, 1});
  for (Tri& t : inverted.triangles) std::swap(t[1], t[2]);
  EXPECT_NEAR(checkSurface(inverted).volume, -1.0, 1e-12);
  EXPECT_NE(validationError(inverted).find("cage is inverted"), std::string::npos);

  const TriMesh overlapping = append(box({0, 0, 0}, {1, 1, 1}), box({0.5, 0.5, 0.5}, {1.5, 1.5, 1.5}));
  const SurfaceCheck c = checkSurface(overlapping);
  EXPECT_TRUE(c.closedManifold());
  EXPECT_GT(c.selfIntersections, 0u);
  EXPECT_NE(validationError(overlapping).find("cage intersects itself"), std::string::npos);

  TriMesh unused = box({0, 0, 0}, {1, 1, 1});
  unused.positions.emplace_back(5, 5, 5);
  EXPECT_NE(validationError(unused).find("1 vertex used by no triangle"), std::string::npos);

  TriMesh badIndex = box({0, 0, 0}, {1, 1, 1});
  badIndex.triangles[0][0] = 42;
  EXPECT_NE(validationError(badIndex).find("references vertex 42"), std::string::npos);
}

TEST(SurfaceChecks, CagesFromFiles) {
  const std::string dir = test::tempDir();
  const TriMesh good = box({0, 0, 0}, {10, 20, 30});
  for (const char* ext : {".obj", ".off"}) {
    writeSurface(dir + "/good" + ext, good);
    const TriMesh back = readCage(dir + "/good" + ext);
    EXPECT_EQ(back.triangles, good.triangles);
    TriMesh open = good;
    open.triangles.erase(open.triangles.begin() + 4);
    writeSurface(dir + "/open" + ext, open);
    try {
      readCage(dir + "/open" + ext);
      FAIL() << "no error";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), dir + "/open" + ext + ": cage is not closed: 3 boundary edges");
    }
    TriMesh inverted = good;
    for (Tri& t : inverted.triangles) std::swap(t[0], t[1]);
    writeSurface(dir + "/inverted" + ext, inverted);
    EXPECT_THROW(readCage(dir + "/inverted" + ext), InputError);
  }
}

TEST(SurfaceChecks, InsideTestOnSphere) {
  const Eigen::Vector3d centre(1.0, -2.0, 3.0);
  const TriMesh s = sphere(centre, 10.0, 3);
  ASSERT_TRUE(checkSurface(s).validCage());
  const SurfaceInsideTest inside(s);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-12.0, 12.0);
  int checked = 0;
  for (int n = 0; n < 20000; ++n) {
    const Eigen::Vector3d p = centre + Eigen::Vector3d(u(rng), u(rng), u(rng));
    const double r = (p - centre).norm();
    // The inscribed polyhedron lies between radius 10 cos(edge angle) and 10.
    if (r > 9.9 && r < 10.01) continue;
    ++checked;
    ASSERT_EQ(inside.contains(p), r < 10.0) << p.transpose();
  }
  EXPECT_GT(checked, 15000);
}

// Rays through edges and vertices: a box whose vertices sit exactly on voxel
// centres' rows. Simulation of simplicity must count each crossing once.
TEST(SurfaceChecks, VoxelMaskThroughEdgesAndVertices) {
  GridGeometry g;
  g.dims = {10, 10, 10};
  const TriMesh b = box({2, 2, 2}, {6, 7, 5});
  const std::vector<std::uint8_t> mask = SurfaceInsideTest(b).voxelMask(g);
  const SurfaceInsideTest inside(b);
  std::int64_t count = 0;
  for (std::int64_t k = 0; k < 10; ++k)
    for (std::int64_t j = 0; j < 10; ++j)
      for (std::int64_t i = 0; i < 10; ++i) {
        const bool m = mask[std::size_t(g.index(i, j, k))];
        count += m;
        EXPECT_EQ(m, inside.contains(g.voxelCenter(i, j, k))) << i << " " << j << " " << k;
        // Rows strictly inside along y and z: inside between the x faces
        // (centres on the faces themselves may go either way).
        if (j > 2 && j < 7 && k > 2 && k < 5 && i != 2 && i != 6) {
          EXPECT_EQ(m, i > 2 && i < 6) << i << " " << j << " " << k;
        }
        if (j < 2 || j > 7 || k < 2 || k > 5 || i < 2 || i > 6) {
          EXPECT_FALSE(m);
        }
      }
  // Centres on the boundary planes go to one side or the other, but each
  // row's count is consistent: at most the closed box, at least the open one.
  EXPECT_GE(count, 3 * 4 * 2);
  EXPECT_LE(count, 5 * 6 * 4);
}

TEST(SurfaceChecks, ForegroundOutsideCount) {
  GridGeometry g;
  g.dims = {8, 8, 8};
  LabelGrid grid(g, 0);
  for (std::int64_t k = 2; k < 6; ++k)
    for (std::int64_t j = 2; j < 6; ++j)
      for (std::int64_t i = 2; i < 6; ++i) grid.at(i, j, k) = 1;
  EXPECT_EQ(countForegroundOutside(box({1.5, 1.5, 1.5}, {5.5, 5.5, 5.5}), grid), 0);
  // Cut off the slab i = 5.
  EXPECT_EQ(countForegroundOutside(box({1.5, 1.5, 1.5}, {4.5, 5.5, 5.5}), grid), 16);
}

}  // namespace
}  // namespace vox
