// Tagged features (thesis 2.3.8): sharp creases of the outer boundary and
// user polylines, kept by the remesher: every input line within 0.1 l of the
// output's tagged edges and back, corners where they were.

#include "geometry/error.h"
#include "geometry/remesh/adaptive_voxel_tetrahedralization.h"
#include "geometry/remesh/feature_edges.h"
#include "geometry/remesh/mesh_topology.h"
#include "geometry/remesh/remesh.h"
#include "geometry/voxel_tetrahedralization.h"

#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

namespace vox::remesh {
namespace {

double distanceToSegment(const FeatureSegment& s, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = s[1] - s[0];
  const double t = std::clamp((p - s[0]).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (s[0] + t * d - p).norm();
}

// Largest distance from points along `from` (every `step` mm) to `to`.
double oneSidedDistance(const std::vector<FeatureSegment>& from, const std::vector<FeatureSegment>& to, double step) {
  double worst = 0.0;
  for (const FeatureSegment& s : from) {
    const int n = std::max(1, int(std::ceil((s[1] - s[0]).norm() / step)));
    for (int i = 0; i <= n; ++i) {
      const Eigen::Vector3d p = s[0] + (s[1] - s[0]) * (double(i) / n);
      double best = std::numeric_limits<double>::infinity();
      for (const FeatureSegment& t : to) best = std::min(best, distanceToSegment(t, p));
      worst = std::max(worst, best);
    }
  }
  return worst;
}

std::vector<FeatureSegment> segmentsOf(const std::vector<Eigen::Vector3d>& positions, const std::vector<TaggedEdge>& edges) {
  std::vector<FeatureSegment> out;
  for (const TaggedEdge& e : edges) out.push_back({positions[std::size_t(e.a)], positions[std::size_t(e.b)]});
  return out;
}

double totalLength(const std::vector<FeatureSegment>& segments) {
  double sum = 0.0;
  for (const FeatureSegment& s : segments) sum += (s[1] - s[0]).norm();
  return sum;
}

// Corners of the tagged lines: vertices with other than two tagged edges,
// edges of two lines, or marked at a kink.
std::vector<Eigen::Vector3d> cornersOf(const RemeshComplex& complex) {
  std::map<std::int32_t, std::set<std::int32_t>> lines;
  std::map<std::int32_t, int> degree;
  for (const TaggedEdge& e : complex.features().list())
    for (std::int32_t v : {e.a, e.b}) {
      lines[v].insert(e.line);
      ++degree[v];
    }
  std::vector<Eigen::Vector3d> out;
  for (const auto& [v, d] : degree)
    if (d != 2 || lines[v].size() != 1 || complex.features().isCorner(v)) out.push_back(complex.position(v));
  return out;
}

void expectCornersKept(const std::vector<Eigen::Vector3d>& corners, const TetMesh& output) {
  for (const Eigen::Vector3d& c : corners) {
    double best = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& p : output.positions) best = std::min(best, (p - c).norm());
    EXPECT_EQ(best, 0.0) << "corner " << c.transpose();
  }
}

void expectValid(const TetMesh& output, const std::vector<TaggedEdge>& edges) {
  double minVolume = std::numeric_limits<double>::infinity();
  std::set<std::pair<std::int32_t, std::int32_t>> meshEdges;
  for (const Tet& t : output.tets) {
    minVolume = std::min(minVolume, signedVolume(output.positions, t));
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) meshEdges.insert(std::minmax(t[std::size_t(i)], t[std::size_t(j)]));
  }
  EXPECT_GT(minVolume, 0.0);
  for (const TaggedEdge& e : edges) EXPECT_TRUE(meshEdges.count({e.a, e.b})) << "tagged edge " << e.a << "-" << e.b << " is no edge";
}

// A 16 mm cube with a 4 mm wide, 6 mm deep notch across its top face.
LabelGrid notchedCube() {
  GridGeometry g;
  g.dims = {24, 24, 24};
  LabelGrid grid(g, 0);
  for (int z = 4; z < 20; ++z)
    for (int y = 4; y < 20; ++y)
      for (int x = 4; x < 20; ++x)
        if (!(x >= 10 && x < 14 && z >= 14)) grid.at(x, y, z) = 1;
  return grid;
}

TEST(FeatureEdges, NotchedCubeKeepsEverySharpEdgeAndCorner) {
  const LabelGrid grid = notchedCube();
  const double l = 3.0;
  const TetMesh initial = tetrahedralizeVoxelsAdaptive(grid, adaptiveOptionsForTarget(grid.geometry(), l));
  RemeshComplex complex(initial);
  RemeshOptions options;
  options.targetLength = l;
  options.iterations = 4;
  options.flipSmoothCycles = 2;
  options.sharpFeatures = true;
  RemeshStats stats;
  tagFeatures(complex, options, &stats);
  const std::vector<FeatureSegment> input = segmentsOf(complex.positions(), complex.features().list());
  // Ten faces (patches), 24 lines between them: the bottom square (64 mm),
  // the four vertical edges (64 mm), the top faces' edges on either side of
  // the notch (2 x (16 + 6 + 6 + 16) mm), the notch's walls (4 x 6 mm at
  // the front and back, 2 x 16 mm along the floor) and floor (2 x 4 mm):
  // 280 mm of creases, and 16 corners where three faces meet.
  EXPECT_NEAR(totalLength(input), 280.0, 1e-9);
  const std::vector<Eigen::Vector3d> corners = cornersOf(complex);
  EXPECT_EQ(corners.size(), 16u);
  EXPECT_EQ(stats.featureLines, 24u);

  remeshComplex(complex, options, &stats);
  std::vector<TaggedEdge> edges;
  const TetMesh output = complex.toTetMesh(false, &edges);
  ASSERT_FALSE(edges.empty());
  expectValid(output, edges);
  EXPECT_EQ(test::joinLines(compareTopology(computeGridTopology(grid), computeMeshTopology(output))), "");
  const std::vector<FeatureSegment> kept = segmentsOf(output.positions, edges);
  EXPECT_LT(oneSidedDistance(input, kept, 0.05 * l), 0.1 * l);
  EXPECT_LT(oneSidedDistance(kept, input, 0.05 * l), 0.1 * l);
  EXPECT_NEAR(totalLength(kept), 280.0, 0.01 * 280.0);
  expectCornersKept(corners, output);
  // The lines were coarsened towards l, not left at the voxels' edges.
  EXPECT_LT(edges.size(), 280u / 2);
}

// An L-shaped polyline on the top face of a cube (on the voxels' edges): the
// line is kept, its end points and its bend (a right angle) exactly.
TEST(FeatureEdges, UserPolylineIsKeptWithItsEndsAndBend) {
  GridGeometry g;
  g.dims = {20, 20, 20};
  LabelGrid grid(g, 0);
  for (int z = 3; z < 17; ++z)
    for (int y = 3; y < 17; ++y)
      for (int x = 3; x < 17; ++x) grid.at(x, y, z) = 1;
  const TetMesh initial = tetrahedralizeVoxels(grid);
  const Eigen::Vector3d a(4.5, 5.5, 16.5), bend(12.5, 5.5, 16.5), b(12.5, 13.5, 16.5);
  const std::vector<FeatureSegment> polyline = {{a, bend}, {bend, b}};
  const double l = 2.5;
  RemeshOptions options;
  options.targetLength = l;
  options.iterations = 4;
  options.flipSmoothCycles = 2;
  options.featureSegments = &polyline;
  RemeshStats stats;
  std::vector<TaggedEdge> edges;
  const TetMesh output = remeshTetMesh(initial, options, &stats, false, "cube", &edges);
  EXPECT_EQ(stats.featureLines, 1u);
  EXPECT_EQ(stats.featureEdges, 16u);  // the voxels' edges along 16 mm
  ASSERT_FALSE(edges.empty());
  expectValid(output, edges);
  EXPECT_EQ(test::joinLines(compareTopology(computeGridTopology(grid), computeMeshTopology(output))), "");
  const std::vector<FeatureSegment> kept = segmentsOf(output.positions, edges);
  EXPECT_LT(oneSidedDistance(polyline, kept, 0.05 * l), 0.1 * l);
  EXPECT_LT(oneSidedDistance(kept, polyline, 0.05 * l), 0.1 * l);
  expectCornersKept({a, bend, b}, output);
  for (const TaggedEdge& e : edges) EXPECT_EQ(e.line, 0);
}

LabelGrid plainCube() {
  GridGeometry g;
  g.dims = {20, 20, 20};
  LabelGrid grid(g, 0);
  for (int z = 3; z < 17; ++z)
    for (int y = 3; y < 17; ++y)
      for (int x = 3; x < 17; ++x) grid.at(x, y, z) = 1;
  return grid;
}

// A staircase polyline whose right-angle steps are not corners (feature
// angle 100 degrees): coarsening and smoothing it towards l = 3 mm would cut
// its steps by 0.35 mm or more; the line stays within 0.1 l.
TEST(FeatureEdges, LinesAreNotCutAtTheirBends) {
  const LabelGrid grid = plainCube();
  std::vector<FeatureSegment> stairs;
  Eigen::Vector3d p(4.5, 4.5, 16.5);
  for (int step = 0; step < 8; ++step)
    for (const Eigen::Vector3d& d : {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0)}) {
      stairs.push_back({p, p + d});
      p += d;
    }
  const double l = 3.0;
  RemeshOptions options;
  options.targetLength = l;
  options.iterations = 4;
  options.flipSmoothCycles = 2;
  options.featureAngle = 100.0;
  options.featureSegments = &stairs;
  std::vector<TaggedEdge> edges;
  const TetMesh output = remeshTetMesh(tetrahedralizeVoxels(grid), options, nullptr, false, "cube", &edges);
  expectValid(output, edges);
  const std::vector<FeatureSegment> kept = segmentsOf(output.positions, edges);
  EXPECT_LT(oneSidedDistance(stairs, kept, 0.05 * l), 0.1 * l);
  EXPECT_LT(oneSidedDistance(kept, stairs, 0.05 * l), 0.1 * l);
}

// A polyline crossing a 1-junction between mesh vertices: where it crosses,
// the vertex is a corner that never moves, so the junction's edge is split
// there (without the split the crossing stays 0.45 mm = 0.18 l away).
TEST(FeatureEdges, PolylineIsInsertedWhereItCrossesAJunction) {
  LabelGrid grid = plainCube();
  for (int z = 3; z < 17; ++z)
    for (int y = 3; y < 17; ++y)
      for (int x = 10; x < 17; ++x) grid.at(x, y, z) = 2;
  const Eigen::Vector3d a(4.5, 4.5, 16.5), b(14.5, 9.5, 16.5), crossing(9.5, 7.0, 16.5);
  const std::vector<FeatureSegment> polyline = {{a, b}};
  const double l = 2.5;
  RemeshOptions options;
  options.targetLength = l;
  options.iterations = 4;
  options.flipSmoothCycles = 2;
  options.featureSegments = &polyline;
  std::vector<TaggedEdge> edges;
  const TetMesh output = remeshTetMesh(tetrahedralizeVoxels(grid), options, nullptr, false, "cube", &edges);
  expectValid(output, edges);
  EXPECT_EQ(test::joinLines(compareTopology(computeGridTopology(grid), computeMeshTopology(output))), "");
  const std::vector<FeatureSegment> kept = segmentsOf(output.positions, edges);
  EXPECT_LT(oneSidedDistance(polyline, kept, 0.05 * l), 0.1 * l);
  EXPECT_LT(oneSidedDistance(kept, polyline, 0.05 * l), 0.1 * l);
  expectCornersKept({a, b, crossing}, output);
}

// Patches smaller than l^2 (a one-voxel bump on a face) join their
// neighbours: only the cube's 12 edges remain.
TEST(FeatureEdges, PatchesSmallerThanTheTargetJoinTheirNeighbours) {
  LabelGrid grid = plainCube();
  grid.at(9, 9, 17) = 1;
  RemeshComplex all(tetrahedralizeVoxels(grid)), merged(tetrahedralizeVoxels(grid));
  // The bump: its top and four sides against each other and the face, 12 more lines.
  EXPECT_EQ(tagSharpFeatures(all, 60.0), 12u + 12u);
  EXPECT_EQ(tagSharpFeatures(merged, 60.0, 9.0), 12u);
  EXPECT_NEAR(totalLength(segmentsOf(merged.positions(), merged.features().list())), 12 * 14.0, 1e-9);
}

TEST(FeatureEdges, PolylineOffTheMeshIsRefusedNamingTheFile) {
  const LabelGrid grid = notchedCube();
  RemeshComplex complex(tetrahedralizeVoxels(grid));
  const std::vector<FeatureSegment> polyline = {{Eigen::Vector3d(4.5, 5.5, 19.5), Eigen::Vector3d(4.5, 9.5, 19.5)},
                                                {Eigen::Vector3d(4.5, 9.5, 19.5), Eigen::Vector3d(4.5, 9.5, 60.0)}};
  try {
    tagPolylines(complex, polyline, 3.0, 60.0, "lines.txt");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("lines.txt"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("segment 2"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(complex.features().empty());
  EXPECT_EQ(complex.features().lineCount(), 0);
}

// The bookkeeping the operations rely on: a split tags both halves, a
// collapse moves the removed vertex's tags to the kept one, renumbering
// follows the vertices.
TEST(FeatureEdges, SplitMergeAndRenumberKeepTheTags) {
  FeatureEdges f;
  const std::int32_t line = f.addLine({});
  f.tag(1, 2, line);
  f.tag(2, 3, line);
  f.split(1, 2, 7);
  EXPECT_EQ(f.lineOf(1, 2), -1);
  EXPECT_EQ(f.lineOf(7, 1), line);
  EXPECT_EQ(f.lineOf(2, 7), line);
  EXPECT_EQ(f.degree(2), 2);
  f.merge(7, 2, {1, 2, 5});
  EXPECT_EQ(f.lineOf(1, 2), line);
  EXPECT_EQ(f.degree(7), 0);
  EXPECT_EQ(f.edgeCount(), 2u);
  f.setCorner(3);
  f.renumber({-1, 4, 0, 1, -1, -1, -1, -1});
  EXPECT_EQ(f.lineOf(4, 0), line);
  EXPECT_EQ(f.lineOf(0, 1), line);
  EXPECT_TRUE(f.isCorner(1));
  EXPECT_FALSE(f.isCorner(3));
}

}  // namespace
}  // namespace vox::remesh
