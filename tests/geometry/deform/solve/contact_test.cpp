#include "geometry/deform/solve/contact.h"
#include "geometry/error.h"
#include "geometry/deform/solve/untangle.h"
#include "geometry/voxel_tetrahedralization.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace vox {
namespace {

// Two 4 x 4 x 4 blocks of unit voxels (six tets each) in one mesh, 36
// apart along z at rest; posed, the upper block let down into the lower by
// 1.5 (its bottom at z = 2.5, the lower's top at z = 4).
struct TwoBlocks {
  TetMesh mesh;
  std::vector<Eigen::Vector3d> posed;
  std::size_t lowerVertices = 0;

  explicit TwoBlocks(double overlap = 1.5, double gap = 40.0) {
    GridGeometry g;
    g.dims = {4, 4, 4};
    g.origin = Eigen::Vector3d::Constant(0.5);  // voxel corners at integers 0..4
    mesh = tetrahedralizeVoxels(LabelGrid(g, 1), {.includeBackground = false});
    lowerVertices = mesh.positions.size();
    const std::size_t tets = mesh.tets.size();
    for (std::size_t v = 0; v < lowerVertices; ++v) mesh.positions.push_back(mesh.positions[v] + Eigen::Vector3d(0, 0, gap));
    for (std::size_t t = 0; t < tets; ++t) {
      Tet u = mesh.tets[t];
      for (auto& v : u) v += std::int32_t(lowerVertices);
      mesh.tets.push_back(u);
      mesh.labels.push_back(mesh.labels[t]);
    }
    posed = mesh.positions;
    for (std::size_t v = lowerVertices; v < posed.size(); ++v) posed[v].z() -= gap - 4.0 + overlap;
  }
};

// The distance from p, inside the box [0,4] x [0,4] x [z0, z0 + 4], to its boundary.
double toBoxBoundary(const Eigen::Vector3d& p, double z0) {
  return std::min({p.x(), 4.0 - p.x(), p.y(), 4.0 - p.y(), p.z() - z0, z0 + 4.0 - p.z()});
}

TEST(Contact, BoundaryFacesOfABlockAreItsSurface) {
  TwoBlocks b;
  const auto faces = boundaryFaces(b.mesh.tets, b.mesh.positions.size());
  // Each block: 6 sides of 4 x 4 squares, two triangles each.
  EXPECT_EQ(faces.size(), 2u * 6u * 16u * 2u);
  // Oriented outwards: the normal points away from the block's centre.
  for (const auto& f : faces) {
    const Eigen::Vector3d a = b.mesh.positions[std::size_t(f[0])], c = b.mesh.positions[std::size_t(f[1])], d = b.mesh.positions[std::size_t(f[2])];
    const Eigen::Vector3d centre = a.z() < 20 ? Eigen::Vector3d(2, 2, 2) : Eigen::Vector3d(2, 2, 42);
    EXPECT_GT((c - a).cross(d - a).dot((a + c + d) / 3.0 - centre), 0.0);
  }
}

TEST(Contact, FindsEachSidesVerticesThroughTheOtherAndTheBoundaryTheyCrossed) {
  TwoBlocks b;
  const std::vector<std::uint8_t> all(b.mesh.positions.size(), 1), penetrable(b.mesh.tets.size(), 1);
  const std::vector<Penetration> found = findPenetrations(b.mesh.positions, b.mesh.tets, b.posed, all, penetrable);
  // The upper block's bottom vertices strictly inside the lower block (3 x
  // 3 of them) and the lower block's top vertices inside the upper one.
  ASSERT_EQ(found.size(), 18u);
  for (const Penetration& p : found) {
    const bool upper = std::size_t(p.vertex) >= b.lowerVertices;
    const Eigen::Vector3d& x = b.posed[std::size_t(p.vertex)];
    EXPECT_NEAR(x.z(), upper ? 2.5 : 4.0, 1e-12);
    // The nearest point of the other block's boundary.
    const double other = upper ? 0.0 : 2.5;
    EXPECT_NEAR(p.depth, toBoxBoundary(x, other), 1e-9) << p.vertex;
    EXPECT_NEAR((p.surface - x).norm(), p.depth, 1e-12);
    for (const std::int32_t u : p.face) EXPECT_NE(std::size_t(u) >= b.lowerVertices, upper);
  }
  EXPECT_TRUE(std::is_sorted(found.begin(), found.end(), [](const Penetration& a, const Penetration& c) { return a.vertex < c.vertex; }));
}

// Two surfaces that cross between their vertices: a wedge (a triangular
// prism, 40 above at rest) let down so that its lower edge runs 1 below the
// block's top along y = 2.5, 0.8 wide at the top's height (the top's
// vertices at y = 2 and 3 outside it), no vertex of either inside the other. The vertices see nothing; the centroids of the
// block's top faces beside the edge (y = 2 1/3 and 2 2/3) lie inside the
// wedge (faceCentroids), each with its face's three vertices, as do the
// wedge's long side faces' inside the block.
TEST(Contact, FaceCentroidsFindTheLensBetweenTheVertices) {
  TwoBlocks b;
  TetMesh mesh;
  mesh.positions.assign(b.mesh.positions.begin(), b.mesh.positions.begin() + std::ptrdiff_t(b.lowerVertices));
  mesh.tets.assign(b.mesh.tets.begin(), b.mesh.tets.begin() + std::ptrdiff_t(b.mesh.tets.size() / 2));
  std::vector<Eigen::Vector3d> posed = mesh.positions;
  const auto w = std::int32_t(mesh.positions.size());
  for (const double x : {-1.0, 5.0})
    for (const Eigen::Vector3d& p : {Eigen::Vector3d(x, 2.5, 3.0), Eigen::Vector3d(x, 1.5, 5.5), Eigen::Vector3d(x, 3.5, 5.5)}) {
      posed.push_back(p);
      mesh.positions.push_back(p + Eigen::Vector3d(0, 0, 40));
    }
  // The prism (a0 l0 r0, a1 l1 r1) as three tets of positive volume.
  for (Tet t : {Tet{0, 1, 2, 3}, Tet{1, 2, 3, 4}, Tet{2, 3, 4, 5}}) {
    for (auto& v : t) v += w;
    if ((posed[std::size_t(t[1])] - posed[std::size_t(t[0])]).cross(posed[std::size_t(t[2])] - posed[std::size_t(t[0])]).dot(
            posed[std::size_t(t[3])] - posed[std::size_t(t[0])]) < 0)
      std::swap(t[2], t[3]);
    mesh.tets.push_back(t);
  }
  const std::vector<std::uint8_t> all(mesh.positions.size(), 1), penetrable(mesh.tets.size(), 1);
  EXPECT_TRUE(findPenetrations(mesh.positions, mesh.tets, posed, all, penetrable).empty());
  ContactOptions options;
  options.faceCentroids = true;
  const std::vector<Penetration> found = findPenetrations(mesh.positions, mesh.tets, posed, all, penetrable, options);
  ASSERT_FALSE(found.empty());
  int blockTop = 0;
  for (const Penetration& p : found) {
    EXPECT_EQ(p.vertex, -1);
    const Eigen::Vector3d c = (posed[std::size_t(p.of[0])] + posed[std::size_t(p.of[1])] + posed[std::size_t(p.of[2])]) / 3.0;
    const bool block = p.of[0] < w;
    for (const std::int32_t u : p.of) EXPECT_EQ(u < w, block);
    for (const std::int32_t u : p.face) EXPECT_NE(u < w, block);  // the other body's boundary
    EXPECT_GT(p.depth, 0.1);
    EXPECT_LT(p.depth, 1.0);
    if (block) {
      // The block's top faces beside the wedge's edge.
      EXPECT_NEAR(c.z(), 4.0, 1e-12);
      EXPECT_NEAR(std::abs(c.y() - 2.5), 1.0 / 6.0, 1e-12);
      ++blockTop;
    }
  }
  EXPECT_GT(blockTop, 0);
}

TEST(Contact, TwoSidesOfACutThatTouchAtRestPressedIntoEachOther) {
  // The blocks touch at rest (a cut's two faces, coincident): within the
  // rest separation, so by distance alone nothing is found; as two sides,
  // each block's vertices through the other are.
  TwoBlocks b(1.5, 4.0);
  const std::vector<std::uint8_t> all(b.mesh.positions.size(), 1), penetrable(b.mesh.tets.size(), 1);
  EXPECT_TRUE(findPenetrations(b.mesh.positions, b.mesh.tets, b.posed, all, penetrable).empty());
  ContactOptions options;
  options.side.assign(b.mesh.positions.size(), 0);
  for (std::size_t v = b.lowerVertices; v < options.side.size(); ++v) options.side[v] = 1;
  const std::vector<Penetration> found = findPenetrations(b.mesh.positions, b.mesh.tets, b.posed, all, penetrable, options);
  ASSERT_EQ(found.size(), 18u);
  for (const Penetration& p : found) {
    const bool upper = std::size_t(p.vertex) >= b.lowerVertices;
    EXPECT_NEAR(p.depth, toBoxBoundary(b.posed[std::size_t(p.vertex)], upper ? 0.0 : 2.5), 1e-9) << p.vertex;
    for (const std::int32_t u : p.face) EXPECT_NE(std::size_t(u) >= b.lowerVertices, upper);
  }
  // At rest the touching faces are contact, not penetration.
  EXPECT_TRUE(findPenetrations(b.mesh.positions, b.mesh.tets, b.mesh.positions, all, penetrable, options).empty());
  // A vertex of several sides (-1) counts by distance alone.
  options.side.assign(b.mesh.positions.size(), -1);
  EXPECT_TRUE(findPenetrations(b.mesh.positions, b.mesh.tets, b.posed, all, penetrable, options).empty());
  options.side.resize(3);
  EXPECT_THROW(findPenetrations(b.mesh.positions, b.mesh.tets, b.posed, all, penetrable, options), InputError);
}

TEST(Contact, NothingAtRestOrWithinTheRestSeparationOrWhereNotPenetrable) {
  TwoBlocks b;
  const std::vector<std::uint8_t> all(b.mesh.positions.size(), 1), penetrable(b.mesh.tets.size(), 1);
  EXPECT_TRUE(findPenetrations(b.mesh.positions, b.mesh.tets, b.mesh.positions, all, penetrable).empty());
  // Blocks that lay within the rest separation of each other do not count.
  ContactOptions near;
  near.restSeparationMm = 50.0;
  EXPECT_TRUE(findPenetrations(b.mesh.positions, b.mesh.tets, b.posed, all, penetrable, near).empty());
  // Only the candidates are tested, only penetrable tets are entered.
  std::vector<std::uint8_t> upperOnly(all.size(), 0), lowerTets(b.mesh.tets.size(), 0);
  std::fill(upperOnly.begin() + std::ptrdiff_t(b.lowerVertices), upperOnly.end(), 1);
  EXPECT_EQ(findPenetrations(b.mesh.positions, b.mesh.tets, b.posed, upperOnly, penetrable).size(), 9u);
  std::fill(lowerTets.begin(), lowerTets.begin() + std::ptrdiff_t(b.mesh.tets.size() / 2), 1);
  for (const Penetration& p : findPenetrations(b.mesh.positions, b.mesh.tets, b.posed, all, lowerTets))
    EXPECT_GE(std::size_t(p.vertex), b.lowerVertices);
  // Touching is contact, not penetration.
  TwoBlocks touching(0.0);
  EXPECT_TRUE(findPenetrations(touching.mesh.positions, touching.mesh.tets, touching.posed, all, penetrable).empty());
}

// The contact solve: the upper block's lowest layers drawn out of the lower one by
// anchors on the crossed boundary (the untangling's energy, lowestEnergy),
// no tet inverted; without lowestEnergy the positions would not change,
// since no tet was inverted to begin with.
TEST(Contact, AnchorsOnTheCrossedBoundaryPartTheBlocks) {
  for (const bool lowest : {true, false}) {
    TwoBlocks b;
    const std::vector<std::uint8_t> all(b.mesh.positions.size(), 1), penetrable(b.mesh.tets.size(), 1);
    std::vector<std::uint8_t> free(b.mesh.positions.size(), 0);
    for (std::size_t v = b.lowerVertices; v < free.size(); ++v) free[v] = b.posed[v].z() < 5.0;  // the upper block's lowest layers
    std::vector<UntangleAnchor> anchors;
    for (const Penetration& p : findPenetrations(b.mesh.positions, b.mesh.tets, b.posed, all, penetrable))
      if (free[std::size_t(p.vertex)]) anchors.push_back({p.vertex, Eigen::Vector3d(b.posed[std::size_t(p.vertex)].x(), b.posed[std::size_t(p.vertex)].y(), 4.0), 100.0});
    ASSERT_EQ(anchors.size(), 9u);
    UntangleOptions o;
    o.lowestEnergy = lowest;
    const std::vector<Eigen::Vector3d> before = b.posed;
    const UntangleReport r = untangleTets(b.mesh.positions, b.mesh.tets, free, anchors, b.posed, o);
    EXPECT_EQ(r.invertedAfter, 0u);
    for (const Tet& t : b.mesh.tets) EXPECT_GT(signedVolume(b.posed, t), 0.0);
    if (!lowest) {
      EXPECT_EQ(b.posed, before);
      continue;
    }
    const std::vector<Penetration> left = findPenetrations(b.mesh.positions, b.mesh.tets, b.posed, all, penetrable);
    double deepest = 0.0;
    for (const Penetration& p : left) deepest = std::max(deepest, p.depth);
    // 1.5 deep before; the anchors against the tissue's stiffness (a third
    // of the block squeezed into the rest) take it most of the way.
    EXPECT_LT(deepest, 0.75) << left.size() << " left";
  }
}

}  // namespace
}  // namespace vox
