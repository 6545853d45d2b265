#include "tests/geometry/deform/cage_fixtures.h"
#include "geometry/deform/solve/cage_arap.h"
#include "geometry/deform/solve/sparse_cholesky.h"
#include "geometry/error.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace vox {
namespace {

Eigen::MatrixX3d targetsOf(const std::vector<Eigen::Vector3d>& positions, const std::vector<std::int32_t>& handles) {
  Eigen::MatrixX3d t(Eigen::Index(handles.size()), 3);
  for (std::size_t k = 0; k < handles.size(); ++k) t.row(Eigen::Index(k)) = positions[std::size_t(handles[k])].transpose();
  return t;
}

// Box-shaped bar along x, [0, 10] x [0, 1] x [0, 1], split 10 x 1 x 1.
TriMesh bar() { return test::subdividedBox({0, 0, 0}, {10, 1, 1}, {10, 2, 2}); }

std::vector<std::int32_t> verticesWhere(const TriMesh& m, auto&& predicate) {
  std::vector<std::int32_t> out;
  for (std::size_t v = 0; v < m.vertexCount(); ++v)
    if (predicate(m.positions[v])) out.push_back(std::int32_t(v));
  return out;
}

TEST(SparseCholesky, SolvesAndRejectsSingular) {
  // 1D Laplacian with one end pinned: SPD.
  const int n = 50;
  std::vector<Eigen::Triplet<double>> t;
  for (int i = 0; i < n; ++i) {
    t.emplace_back(i, i, i == n - 1 ? 1.0 : 2.0);
    if (i > 0) t.emplace_back(i, i - 1, -1.0);
  }
  Eigen::SparseMatrix<double> a(n, n);
  a.setFromTriplets(t.begin(), t.end());  // lower triangle only
  SparseCholesky chol;
  chol.factorize(a);
  const Eigen::MatrixXd b = Eigen::MatrixXd::Random(n, 3);
  const Eigen::MatrixXd x = chol.solve(b);
  const Eigen::SparseMatrix<double> full = a.selfadjointView<Eigen::Lower>();
  EXPECT_LT((full * x - b).norm(), 1e-10 * b.norm());

  // Pure Neumann Laplacian: singular.
  std::vector<Eigen::Triplet<double>> s;
  for (int i = 0; i < n; ++i) {
    s.emplace_back(i, i, (i == 0 || i == n - 1) ? 1.0 : 2.0);
    if (i > 0) s.emplace_back(i, i - 1, -1.0);
  }
  Eigen::SparseMatrix<double> singular(n, n);
  singular.setFromTriplets(s.begin(), s.end());
  EXPECT_THROW(chol.factorize(singular), RuntimeFailure);
}

TEST(CageArap, RestTargetsKeepTheRestShape) {
  const TriMesh cage = test::bumpyCage(2, 100.0, 0.3, {10, 20, 30});
  CageArap arap;
  const std::vector<std::int32_t> handles{0, 5, 17, 40};
  arap.precompute(cage, handles);
  const auto& out = arap.solve(targetsOf(cage.positions, handles), 5);
  double worst = 0;
  for (std::size_t v = 0; v < cage.vertexCount(); ++v) worst = std::max(worst, (out[v] - cage.positions[v]).norm());
  EXPECT_LT(worst, 1e-9);
}

TEST(CageArap, RigidHandleMotionGivesRigidCage) {
  const TriMesh cage = test::bumpyCage(2, 100.0, 0.3, {10, 20, 30});
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.8, Eigen::Vector3d(0.3, 1, -0.2).normalized()).toRotationMatrix();
  const Eigen::Vector3d shift(5, -7, 12);
  std::vector<Eigen::Vector3d> moved;
  for (const auto& p : cage.positions) moved.push_back(r * p + shift);
  const std::vector<std::int32_t> handles{0, 33, 77, 120, 150};
  CageArap arap;
  arap.precompute(cage, handles);
  std::vector<double> energies;
  const Eigen::MatrixX3d targets = targetsOf(moved, handles);
  for (int round = 0; round < 40; ++round) {
    arap.solve(targets, 5);
    energies.push_back(arap.energy(arap.positions()));
  }
  // Local/global never increases the (clamped-weight) energy.
  for (std::size_t k = 1; k < energies.size(); ++k) EXPECT_LE(energies[k], energies[k - 1] * (1 + 1e-12) + 1e-18) << k;
  double worst = 0;
  for (std::size_t v = 0; v < cage.vertexCount(); ++v) worst = std::max(worst, (arap.positions()[v] - moved[v]).norm());
  RecordProperty("rigid_error_mm", std::to_string(worst));
  EXPECT_LT(worst, 1e-5 * 200.0);  // 200 iterations of a linearly converging scheme
}

TEST(CageArap, NegativeCotangentWeightsAreClamped) {
  // A flattened sphere has many obtuse angle pairs.
  TriMesh cage = test::icosphere(2);
  for (auto& p : cage.positions) p.z() *= 0.15;
  CageArap arap;
  const std::vector<std::int32_t> handles{0, 1};
  arap.precompute(cage, handles);
  EXPECT_GT(arap.clampedWeightCount(), 0u);
  for (double w : arap.weights()) EXPECT_GT(w, 0.0);
  Eigen::MatrixX3d targets = targetsOf(cage.positions, handles);
  targets.row(1) += Eigen::RowVector3d(0.2, 0.1, 0.0);
  const auto& out = arap.solve(targets, 10);
  for (const auto& p : out) EXPECT_TRUE(p.allFinite());
}

TEST(CageArap, BendsABarSmoothly) {
  const TriMesh cage = bar();
  const auto fixedEnd = verticesWhere(cage, [](const Eigen::Vector3d& p) { return p.x() < 1e-9; });
  const auto movingEnd = verticesWhere(cage, [](const Eigen::Vector3d& p) { return p.x() > 10 - 1e-9; });
  std::vector<std::int32_t> handles = fixedEnd;
  handles.insert(handles.end(), movingEnd.begin(), movingEnd.end());
  CageArap arap;
  arap.precompute(cage, handles);
  // Moving end: where bending the centre line (y = 0.5) into a quarter
  // circle of the same length puts it, (10, y, z) -> (rho - (y - 0.5), 0.5 + rho, z).
  const double rho = 10.0 / (std::numbers::pi / 2);
  std::vector<Eigen::Vector3d> goal = cage.positions;
  for (std::int32_t v : movingEnd) {
    const Eigen::Vector3d& p = cage.positions[std::size_t(v)];
    goal[std::size_t(v)] = Eigen::Vector3d(rho - (p.y() - 0.5), 0.5 + rho, p.z());
  }
  const auto& out = arap.solve(targetsOf(goal, handles), 200);
  // The one-call form gives the same result.
  const auto once = arapDeformCage(cage, handles, targetsOf(goal, handles), 200);
  for (std::size_t v = 0; v < once.size(); ++v) EXPECT_LT((once[v] - out[v]).norm(), 1e-12);
  // Edge lengths stay within 25% of the rest lengths in a strong bend.
  double worst = 0;
  for (const auto& e : arap.edges()) {
    const double rest = (cage.positions[std::size_t(e[0])] - cage.positions[std::size_t(e[1])]).norm();
    const double now = (out[std::size_t(e[0])] - out[std::size_t(e[1])]).norm();
    worst = std::max(worst, std::abs(now / rest - 1.0));
  }
  RecordProperty("bar_bend_max_edge_strain", std::to_string(worst));
  EXPECT_LT(worst, 0.25);
}

// Most vertices handles, a few free between a fixed and a rotated part (the
// poses' case: a joint's ring free, the limbs and the body held). The local
// step fits only the rotations the global step reads; the result must still
// be a minimum of the whole energy, whose rotations are all fitted
// (energy()): no small move of a free vertex lowers it.
TEST(CageArap, FewFreeVerticesReachAnEnergyMinimum) {
  const TriMesh cage = bar();
  std::vector<std::int32_t> handles = verticesWhere(cage, [](const Eigen::Vector3d& p) { return std::abs(p.x() - 5) > 0.5; });
  const auto freeVertices = verticesWhere(cage, [](const Eigen::Vector3d& p) { return std::abs(p.x() - 5) <= 0.5; });
  ASSERT_EQ(freeVertices.size(), 8u);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(std::numbers::pi / 6, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d centre(5, 0.5, 0.5);
  std::vector<Eigen::Vector3d> goal = cage.positions;
  for (auto& p : goal)
    if (p.x() > 5.5) p = centre + r * (p - centre);
  CageArap arap;
  arap.precompute(cage, handles);
  std::vector<Eigen::Vector3d> out = arap.solve(targetsOf(goal, handles), 500);
  const double e0 = arap.energy(out);
  double worstDrop = 0;
  for (const std::int32_t v : freeVertices)
    for (int axis = 0; axis < 3; ++axis)
      for (const double h : {-1e-3, 1e-3}) {
        std::vector<Eigen::Vector3d> moved = out;
        moved[std::size_t(v)][axis] += h;
        worstDrop = std::max(worstDrop, e0 - arap.energy(moved));
      }
  RecordProperty("largest_energy_drop", std::to_string(worstDrop));
  EXPECT_LE(worstDrop, 1e-9 * std::max(e0, 1.0));
}

TEST(CageArap, RejectsBadHandleSets) {
  const TriMesh cage = test::icosphere(1);
  CageArap arap;
  const std::vector<std::int32_t> none;
  EXPECT_THROW(arap.precompute(cage, none), InputError);
  const std::vector<std::int32_t> outOfRange{0, 1000};
  EXPECT_THROW(arap.precompute(cage, outOfRange), InputError);
  const std::vector<std::int32_t> repeated{3, 3};
  EXPECT_THROW(arap.precompute(cage, repeated), InputError);
  // Two disjoint spheres, handles on one only.
  TriMesh two = cage;
  const auto offset = std::int32_t(cage.vertexCount());
  for (const auto& p : cage.positions) two.positions.push_back(p + Eigen::Vector3d(5, 0, 0));
  for (const Tri& t : cage.triangles) two.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const std::vector<std::int32_t> oneSide{0, 1};
  try {
    arap.precompute(two, oneSide);
    FAIL() << "a cage part without handles was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("holds no handle"), std::string::npos) << e.what();
  }
}

TEST(CageArap, WarmStartConverges) {
  const TriMesh cage = bar();
  const auto fixedEnd = verticesWhere(cage, [](const Eigen::Vector3d& p) { return p.x() < 1e-9; });
  const auto movingEnd = verticesWhere(cage, [](const Eigen::Vector3d& p) { return p.x() > 10 - 1e-9; });
  std::vector<std::int32_t> handles = fixedEnd;
  handles.insert(handles.end(), movingEnd.begin(), movingEnd.end());
  CageArap arap;
  arap.precompute(cage, handles);
  Eigen::MatrixX3d targets = targetsOf(cage.positions, handles);
  for (std::size_t k = fixedEnd.size(); k < handles.size(); ++k) targets.row(Eigen::Index(k)) += Eigen::RowVector3d(0, 3, 0);
  // Many frames of a few iterations reach what one long solve reaches.
  for (int frame = 0; frame < 60; ++frame) arap.solve(targets, 5);
  const std::vector<Eigen::Vector3d> warm = arap.positions();
  arap.resetWarmStart();
  arap.solve(targets, 300);
  double worst = 0;
  for (std::size_t v = 0; v < warm.size(); ++v) worst = std::max(worst, (warm[v] - arap.positions()[v]).norm());
  EXPECT_LT(worst, 1e-3);
}

}  // namespace
}  // namespace vox
