// What the rounds screen on all threads stands for what they then apply:
// a flipper that reads the tets' worst angles from the table made before
// the screening decides as one that computes them, and a collapse applied
// from its one-byte plan leaves the complex the checked collapse leaves.

#include "geometry/remesh/adaptive_voxel_tetrahedralization.h"
#include "geometry/remesh/collapse_short_edges.h"
#include "geometry/remesh/edge_length_bounds.h"
#include "geometry/remesh/flip_edges.h"
#include "geometry/remesh/hull_constraint.h"
#include "geometry/remesh/mesh_edges.h"
#include "geometry/remesh/split_long_edges.h"
#include "geometry/synth.h"

#include <gtest/gtest.h>

#include <cstring>
#include <set>

namespace vox::remesh {
namespace {

struct Input {
  double l = 0.0;
  RemeshComplex complex;
};

// The junction sphere's decomposition at l = 2 voxels, its long edges split
// (short edges to collapse), then with `collapse` its short edges collapsed
// (poor tets and interfaces to flip).
Input junctionSphere(bool collapse = false) {
  const LabelGrid grid = synthesize(SynthKind::JunctionSphere, 16);
  Input in;
  in.l = 2.0 * grid.spacing().maxCoeff();
  in.complex = RemeshComplex(tetrahedralizeVoxelsAdaptive(grid, adaptiveOptionsForTarget(grid.geometry(), in.l)));
  splitLongEdges(in.complex, EdgeLengthBounds::forTarget(in.l), 1);
  if (collapse) collapseShortEdges(in.complex, EdgeLengthBounds::forTarget(in.l), HullConstraint(in.complex), 1);
  return in;
}

std::vector<double> worstCosineTable(const RemeshComplex& c) {
  std::vector<double> table(std::size_t(c.tetSlots()), 2.0);
  for (std::int32_t t = 0; t < c.tetSlots(); ++t)
    if (c.tetAlive(t) && !c.isDummyTet(t)) table[std::size_t(t)] = c.minDihedralCosineOf(t);
  return table;
}

TEST(ScreenedPlans, FlipsReadingTheAngleTableDecideAsFlipsComputingThem) {
  Input in = junctionSphere(true);
  const RemeshComplex& c = in.complex;
  const std::vector<double> table = worstCosineTable(c);
  EdgeFlipper computing(in.complex, FlipOptions{}), reading(in.complex, FlipOptions{});
  reading.useWorstCosines(&table);

  std::set<std::pair<std::int32_t, std::int32_t>> edges;
  for (std::int32_t t = 0; t < c.tetSlots(); ++t) {
    if (!c.tetAlive(t)) continue;
    const Tet& q = c.tet(t);
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) edges.insert(std::minmax(q[std::size_t(i)], q[std::size_t(j)]));
  }
  std::size_t inner = 0, surface = 0, face = 0;
  for (const auto& [a, b] : edges) {
    std::uint8_t apexComputed = 0xFF, apexRead = 0xFF;
    const bool computed = computing.tryFlipInnerEdge(a, b, false, &apexComputed);
    ASSERT_EQ(computed, reading.tryFlipInnerEdge(a, b, false, &apexRead)) << a << " " << b;
    ASSERT_EQ(apexComputed, apexRead);
    inner += computed;
    apexComputed = apexRead = 0xFF;
    const bool flat = computing.tryFlipSurfaceEdge(a, b, false, &apexComputed);
    ASSERT_EQ(flat, reading.tryFlipSurfaceEdge(a, b, false, &apexRead)) << a << " " << b;
    ASSERT_EQ(apexComputed, apexRead);
    surface += flat;
  }
  for (std::int32_t t = 0; t < c.tetSlots(); ++t)
    for (int k = 0; k < 4; ++k) {
      const bool computed = computing.tryFlipFace(t, k, false);
      ASSERT_EQ(computed, reading.tryFlipFace(t, k, false)) << t << " " << k;
      face += computed;
    }
  // Not vacuous: each kind finds flips on this complex.
  EXPECT_GT(inner, 0u);
  EXPECT_GT(surface, 0u);
  EXPECT_GT(face, 0u);
  EXPECT_EQ(in.complex.checkConsistency(true), "");  // nothing was applied
}

TEST(ScreenedPlans, ACollapseAppliedFromItsPlanEqualsTheCheckedCollapse) {
  const Input in = junctionSphere();
  const EdgeLengthBounds bounds = EdgeLengthBounds::forTarget(in.l);
  const double emin2 = bounds.emin * bounds.emin;
  std::vector<WeightedEdge> shortEdges;
  collectEdges(in.complex, [&](std::int32_t, std::int32_t, double l2) { return l2 < emin2; }, shortEdges, 1);
  ASSERT_FALSE(shortEdges.empty());

  RemeshComplex screened = in.complex;
  const HullConstraint hull(screened);
  EdgeCollapser screen(screened, bounds, hull);
  // A plan of each kind, a few of each, made on copies of the complex both ways.
  std::size_t made[4] = {0, 0, 0, 0};
  for (const WeightedEdge& e : shortEdges) {
    CollapseMove move = CollapseMove::None;
    const std::int32_t kept = screen.tryCollapse(e.a, e.b, false, &move);
    ASSERT_EQ(kept < 0, move == CollapseMove::None);
    std::size_t& count = made[std::size_t(move)];
    if (move == CollapseMove::None || count >= 4) continue;
    ++count;
    RemeshComplex fromPlan = in.complex, checked = in.complex;
    const HullConstraint hullPlan(fromPlan), hullChecked(checked);
    EXPECT_EQ(EdgeCollapser(fromPlan, bounds, hullPlan).applyPlan(e.a, e.b, move), kept);
    EXPECT_EQ(EdgeCollapser(checked, bounds, hullChecked).tryCollapse(e.a, e.b), kept);
    const TetMesh x = fromPlan.toTetMesh(true), y = checked.toTetMesh(true);
    ASSERT_EQ(x.tets, y.tets);
    ASSERT_EQ(x.labels, y.labels);
    ASSERT_EQ(x.positions.size(), y.positions.size());
    EXPECT_EQ(std::memcmp(x.positions.data(), y.positions.data(), x.positions.size() * sizeof(Eigen::Vector3d)), 0);
    EXPECT_EQ(fromPlan.checkConsistency(true), "");
  }
  EXPECT_GT(made[std::size_t(CollapseMove::ToMidpoint)], 0u);
  EXPECT_GT(made[std::size_t(CollapseMove::UOntoV)] + made[std::size_t(CollapseMove::VOntoU)], 0u);
}

}  // namespace
}  // namespace vox::remesh
