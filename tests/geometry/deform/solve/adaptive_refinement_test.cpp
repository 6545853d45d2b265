#include "geometry/deform/solve/adaptive_refinement.h"

#include "geometry/deform/solve/deformation_metrics.h"
#include "geometry/error.h"
#include "geometry/mesh_quality.h"
#include "geometry/raster/field_interpolation.h"
#include "geometry/voxel_tetrahedralization.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <set>

namespace vox {
namespace {

// Six-tet mesh of an nx x ny x nz block of unit voxels, vertices at
// (i - 1/2, j - 1/2, k - 1/2); the grid of its voxels.
GridGeometry blockGrid(int nx, int ny, int nz) {
  GridGeometry g;
  g.dims = {nx, ny, nz};
  return g;
}

TetMesh block(const GridGeometry& g) { return tetrahedralizeVoxels(LabelGrid(g, 1), {.includeBackground = false}); }

// A shear confined to a slab around x = 8: the tets there bend, the others
// translate, so the error is far from uniform.
Eigen::Vector3d bend(const Eigen::Vector3d& p) {
  const double s = p.x() - 8.0;
  return {p.x(), p.y() + 3.0 * std::exp(-s * s / 2.0), p.z()};
}

double volume(const TetMesh& m) {
  double sum = 0.0;
  for (const Tet& t : m.tets) sum += signedVolume(m.positions, t);
  return sum;
}

// The bent block as a refinement subject. The vertices with x < 1 are not
// placed by the deformation (as the propagation's outside a cage): their
// midpoints stay on their edges' images.
struct BentBlock {
  TetMesh rest;
  std::vector<Eigen::Vector3d> deformed;
  std::vector<std::uint8_t> placed;
  std::size_t unplacedParents = 0, adoptions = 0;

  explicit BentBlock(TetMesh mesh) : rest(std::move(mesh)) {
    for (const Eigen::Vector3d& p : rest.positions) {
      deformed.push_back(bend(p));
      placed.push_back(p.x() >= 1.0);
    }
  }

  RefinementSubject subject() {
    return {.restMesh = [this]() -> const TetMesh& { return rest; },
            .deformedPositions = [this]() -> const std::vector<Eigen::Vector3d>& { return deformed; },
            .placedByDeformation = [this] { return placed; },
            .placeMidpoints =
                [this](const TetMesh& refined, std::span<const TetEdge> parents, std::vector<Eigen::Vector3d>& moved,
                       std::vector<std::uint8_t>& known) {
                  for (const TetEdge& e : parents) {
                    const auto a = std::size_t(e[0]), b = std::size_t(e[1]);
                    unplacedParents += !known[a] || !known[b];
                    known.push_back(known[a] && known[b]);
                    moved.push_back(known.back() ? bend(refined.positions[moved.size()]) : 0.5 * (moved[a] + moved[b]));
                  }
                },
            .adopt =
                [this](TetMesh refined, std::vector<Eigen::Vector3d> moved, std::vector<std::uint8_t> known) {
                  rest = std::move(refined);
                  deformed = std::move(moved);
                  placed = std::move(known);
                  ++adoptions;
                }};
  }
};

TEST(AdaptiveRefinement, BisectionSplitsEveryTetOnTheEdgeKeepingOrientationAndVolume) {
  const GridGeometry g = blockGrid(2, 2, 2);
  TetMesh mesh = block(g);
  const TetMesh before = mesh;
  const Tet t0 = mesh.tets[0];
  const TetEdge edge{t0[0], t0[1]};
  std::size_t onEdge = 0;
  for (const Tet& t : mesh.tets) onEdge += std::count(t.begin(), t.end(), edge[0]) && std::count(t.begin(), t.end(), edge[1]);
  EdgeBisection bisection(mesh);
  EXPECT_EQ(bisection.tetsAround(edge).size(), onEdge);
  EXPECT_EQ(bisection.bisect(edge), onEdge);
  EXPECT_EQ(mesh.vertexCount(), before.vertexCount() + 1);
  EXPECT_EQ(mesh.tetCount(), before.tetCount() + onEdge);
  EXPECT_EQ(mesh.labels.size(), mesh.tetCount());
  EXPECT_TRUE(mesh.positions.back().isApprox(0.5 * (before.positions[std::size_t(edge[0])] + before.positions[std::size_t(edge[1])])));
  EXPECT_TRUE(bisection.tetsAround(edge).empty());
  // Another edge of the same tet, then one of a child: the tets of each
  // vertex stay those of the mesh.
  EXPECT_GT(bisection.bisect({t0[2], t0[3]}), 0u);
  const Tet child = mesh.tets.back();
  EXPECT_GT(bisection.bisect({child[0], child[1]}), 0u);
  for (std::int32_t a = 0; a < std::int32_t(mesh.vertexCount()); ++a)
    for (std::int32_t b = a + 1; b < std::int32_t(mesh.vertexCount()); ++b) {
      std::vector<std::int32_t> holding;
      for (std::size_t t = 0; t < mesh.tetCount(); ++t)
        if (std::count(mesh.tets[t].begin(), mesh.tets[t].end(), a) && std::count(mesh.tets[t].begin(), mesh.tets[t].end(), b))
          holding.push_back(std::int32_t(t));
      EXPECT_EQ(bisection.tetsAround({a, b}), holding) << a << " " << b;
    }
  for (const Tet& t : mesh.tets) EXPECT_GT(signedVolume(mesh.positions, t), 0.0);
  EXPECT_NEAR(volume(mesh), volume(before), 1e-12);
  // Conforming: every face is shared by at most two tets (faceNeighbors throws otherwise).
  EXPECT_NO_THROW(faceNeighbors(mesh, "refined"));
  EXPECT_THROW(bisection.bisect({0, 0}), RuntimeFailure);
  EXPECT_THROW(bisection.bisect({edge[0], edge[1]}), RuntimeFailure);
}

TEST(AdaptiveRefinement, SplitsOnlyTheDistortedTetsAndStopsWhenTheErrorStopsImproving) {
  const GridGeometry g = blockGrid(16, 4, 4);
  BentBlock bent(block(g));
  const TetMesh initial = bent.rest;
  const RefinementResult result =
      refineTransferMesh(bent.subject(), g, cpuFieldInterpolation(1), {.maxIterations = 10, .maxTets = 100000});
  for (const RefinementStep& s : result.steps)
    std::cout << "[ stats    ] " << s.tets << " tets, e_g mean " << s.meanError << " max " << s.maxError << ", " << s.splitEdges
              << " edges split\n";
  std::cout << "[ stats    ] stop: " << result.stopReason << "\n";
  ASSERT_GE(result.steps.size(), 2u);
  EXPECT_GT(result.steps[0].splitEdges, 0u);
  // The loop ended on one of its criteria before its round limit, keeping
  // the TM of the lowest max e_g, which the first round improved.
  EXPECT_TRUE(result.stopReason == "stalled" || result.stopReason == "uniform error" || result.stopReason == "unsplittable")
      << result.stopReason;
  EXPECT_LT(result.steps.size(), 11u);
  EXPECT_LT(result.steps[1].maxError, 0.9 * result.steps[0].maxError);
  ASSERT_GE(result.kept, 1u);
  for (const RefinementStep& s : result.steps) EXPECT_GE(s.maxError, result.steps[result.kept].maxError);
  EXPECT_EQ(bent.adoptions, 1u);
  EXPECT_EQ(bent.rest.tetCount(), result.steps[result.kept].tets);
  for (std::size_t k = 1; k < result.steps.size(); ++k) {
    EXPECT_EQ(result.steps[k].vertices, result.steps[k - 1].vertices + result.steps[k - 1].splitEdges);
    EXPECT_GT(result.steps[k].tets, result.steps[k - 1].tets);
  }
  EXPECT_EQ(bent.unplacedParents, 0u);
  EXPECT_EQ(bent.deformed.size(), bent.rest.vertexCount());

  // The refined TM: conforming, positive, the same volume; the tets far
  // from the shear (translated rigidly) are the initial ones, untouched.
  EXPECT_NO_THROW(faceNeighbors(bent.rest, "refined"));
  for (const Tet& t : bent.rest.tets) EXPECT_GT(signedVolume(bent.rest.positions, t), 0.0);
  EXPECT_NEAR(volume(bent.rest), volume(initial), 1e-9);
  const auto far = [](const TetMesh& m, const Tet& t) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const std::int32_t v : t) c += 0.25 * m.positions[std::size_t(v)];
    return std::abs(c.x() - 8.0) > 6.0;
  };
  std::set<Tet> farInitial, farRefined;
  for (const Tet& t : initial.tets)
    if (far(initial, t)) farInitial.insert(t);
  for (const Tet& t : bent.rest.tets)
    if (far(bent.rest, t)) farRefined.insert(t);
  EXPECT_FALSE(farInitial.empty());
  EXPECT_EQ(farInitial, farRefined);
}

// Every tet is bisected by its own longest edge (the longest-edge
// propagation path), so the refined tets keep the initial tets' shapes: on
// the six-tet voxel decomposition the bisections give only tets similar to
// Kuhn's, whose smallest dihedral angle is the initial 45 degrees. A sliver
// would turn the bend, smooth at the tets' scale, into a stretch of its
// basis change beyond the bend's own.
TEST(AdaptiveRefinement, RefinedTetsKeepTheirShapeAndTheStretchOfTheMap) {
  const GridGeometry g = blockGrid(16, 4, 4);
  BentBlock bent(block(g));
  const TetMesh initial = bent.rest;
  const std::vector<Eigen::Vector3d> initialDeformed = bent.deformed;
  const RefinementResult result =
      refineTransferMesh(bent.subject(), g, cpuFieldInterpolation(1), {.maxIterations = 3, .maxTets = 100000});
  ASSERT_GE(result.kept, 1u) << result.stopReason;
  const TetQualitySummary before = summarizeTetQuality(initial), after = summarizeTetQuality(bent.rest);
  const DistortionHistograms bentBefore = distortionHistograms(initial, initialDeformed);
  const DistortionHistograms bentAfter = distortionHistograms(bent.rest, bent.deformed);
  std::cout << "[ stats    ] " << bent.rest.tetCount() << " tets; min dihedral " << before.minDihedral << " -> " << after.minDihedral
            << " deg; max stretch " << bentBefore.stretch.max << " -> " << bentAfter.stretch.max << ", angles "
            << bentBefore.angle.min << "-" << bentBefore.angle.max << " -> " << bentAfter.angle.min << "-" << bentAfter.angle.max << "\n";
  EXPECT_GE(after.minDihedral, before.minDihedral - 1e-9);
  // The bend's largest stretch, of the x axis at |x - 8| = 1: sqrt(1 + 9 / e).
  EXPECT_LE(bentAfter.stretch.max, 1.05 * std::sqrt(1.0 + 9.0 / std::exp(1.0)));
}

TEST(AdaptiveRefinement, StopsAtTheTetBudget) {
  const GridGeometry g = blockGrid(16, 4, 4);
  BentBlock bent(block(g));
  const std::int64_t budget = std::int64_t(bent.rest.tetCount()) + 40;
  const RefinementResult result = refineTransferMesh(bent.subject(), g, cpuFieldInterpolation(1), {.maxIterations = 10, .maxTets = budget});
  EXPECT_LE(std::int64_t(bent.rest.tetCount()), budget);
  EXPECT_TRUE(result.stopReason == "tet budget" || result.stopReason == "stalled") << result.stopReason;
}

TEST(AdaptiveRefinement, ARigidMotionIsNegligibleAndLeavesTheMeshAlone) {
  const GridGeometry g = blockGrid(6, 3, 3);
  BentBlock moved(block(g));
  for (std::size_t v = 0; v < moved.rest.vertexCount(); ++v)
    moved.deformed[v] = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) * moved.rest.positions[v] + Eigen::Vector3d(1, 2, 3);
  const std::size_t tets = moved.rest.tetCount();
  const RefinementResult result = refineTransferMesh(moved.subject(), g, cpuFieldInterpolation(1));
  EXPECT_EQ(result.stopReason, "negligible error");
  EXPECT_EQ(moved.rest.tetCount(), tets);
  EXPECT_EQ(moved.adoptions, 0u);
}

}  // namespace
}  // namespace vox
