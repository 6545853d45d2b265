#include "geometry/deform/solve/deformation_metrics.h"
#include "geometry/deform/solve/propagation.h"
#include "geometry/error.h"
#include "geometry/voxel_tetrahedralization.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <set>

namespace vox {
namespace {

std::string sci(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

// Six-tet mesh of an nx x ny x nz block of unit voxels; vertices at
// (i - 1/2, j - 1/2, k - 1/2) + offset.
TetMesh block(int nx, int ny, int nz, const Eigen::Vector3d& offset = Eigen::Vector3d::Zero()) {
  GridGeometry g;
  g.dims = {nx, ny, nz};
  g.origin = offset;
  const LabelGrid grid(g, 1);
  return tetrahedralizeVoxels(grid, {.includeBackground = false});
}

TetMesh concatenate(const TetMesh& a, const TetMesh& b) {
  TetMesh m = a;
  const auto offset = std::int32_t(a.vertexCount());
  m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
  for (const Tet& t : b.tets) m.tets.push_back({t[0] + offset, t[1] + offset, t[2] + offset, t[3] + offset});
  m.labels.insert(m.labels.end(), b.labels.begin(), b.labels.end());
  return m;
}

std::vector<std::uint8_t> insideWhere(const TetMesh& m, auto&& predicate) {
  std::vector<std::uint8_t> inside(m.vertexCount());
  for (std::size_t v = 0; v < m.vertexCount(); ++v) inside[v] = predicate(m.positions[v]) ? 1 : 0;
  return inside;
}

TEST(Propagation, RigidMotionOfTheInsideMovesTheOutsideRigidly) {
  const TetMesh bar = block(24, 6, 5);
  const auto inside = insideWhere(bar, [](const Eigen::Vector3d& p) { return p.x() < 15.0; });
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.9, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix();
  const Eigen::Vector3d shift(30, -4, 17);
  std::vector<Eigen::Vector3d> positions(bar.vertexCount(), Eigen::Vector3d::Zero());
  for (std::size_t v = 0; v < bar.vertexCount(); ++v)
    if (inside[v]) positions[v] = r * bar.positions[v] + shift;
  RigidityPropagation propagation;
  propagation.precompute(bar, inside);
  EXPECT_GT(propagation.diagnostics().outsideVertexCount, 0u);
  EXPECT_EQ(propagation.diagnostics().unconstrainedTetGroups, 0u);
  EXPECT_EQ(propagation.diagnostics().unconstrainedVertexGroups, 0u);
  propagation.propagate(positions);
  double worst = 0;
  for (std::size_t v = 0; v < bar.vertexCount(); ++v) worst = std::max(worst, (positions[v] - (r * bar.positions[v] + shift)).norm());
  RecordProperty("rigid_error_relative", sci(worst / 24.0));
  EXPECT_LT(worst / 24.0, 1e-9);
  // Every B_t of the outside tets is the rotation.
  for (const auto& b : propagation.unknownTetBasis()) EXPECT_LT((b - r).norm(), 1e-9);
}

// Bend the centre line y = yc of a bar along x into an arc of radius rho:
// (x, y, z) -> (0, yc + rho) + (rho - (y - yc)) (sin(x / rho), -cos(x / rho)).
Eigen::Vector3d bend(const Eigen::Vector3d& p, double yc, double rho) {
  const double theta = p.x() / rho;
  const double u = p.y() - yc;
  return {(rho - u) * std::sin(theta), yc + rho - (rho - u) * std::cos(theta), p.z()};
}

struct EdgeDistortion {
  double maxInside = 0, meanInside = 0, maxOutside = 0, meanOutside = 0;
  std::size_t outsideEdges = 0;
};

EdgeDistortion edgeDistortion(const TetMesh& rest, const std::vector<Eigen::Vector3d>& deformed, const std::vector<std::uint8_t>& inside) {
  std::set<std::pair<std::int32_t, std::int32_t>> edges;
  for (const Tet& t : rest.tets)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) edges.insert(std::minmax(t[std::size_t(a)], t[std::size_t(b)]));
  EdgeDistortion d;
  std::size_t insideEdges = 0;
  for (const auto& [i, j] : edges) {
    const double rest0 = (rest.positions[std::size_t(i)] - rest.positions[std::size_t(j)]).norm();
    const double now = (deformed[std::size_t(i)] - deformed[std::size_t(j)]).norm();
    const double e = std::abs(now / rest0 - 1.0);
    if (inside[std::size_t(i)] && inside[std::size_t(j)]) {
      d.maxInside = std::max(d.maxInside, e);
      d.meanInside += e;
      ++insideEdges;
    } else {
      d.maxOutside = std::max(d.maxOutside, e);
      d.meanOutside += e;
      ++d.outsideEdges;
    }
  }
  d.meanInside /= double(insideEdges);
  d.meanOutside /= double(d.outsideEdges);
  return d;
}

TEST(Propagation, BentBarOutsideDistortionBoundedByInside) {
  const TetMesh bar = block(30, 6, 6);
  const double yc = 2.5, rho = 25.0;
  const auto inside = insideWhere(bar, [](const Eigen::Vector3d& p) { return p.x() < 20.0; });
  std::vector<Eigen::Vector3d> positions(bar.vertexCount(), Eigen::Vector3d::Zero());
  for (std::size_t v = 0; v < bar.vertexCount(); ++v)
    if (inside[v]) positions[v] = bend(bar.positions[v], yc, rho);
  RigidityPropagation propagation;
  propagation.precompute(bar, inside);
  propagation.propagate(positions);
  const EdgeDistortion d = edgeDistortion(bar, positions, inside);
  RecordProperty("inside_max", sci(d.maxInside));
  RecordProperty("inside_mean", sci(d.meanInside));
  RecordProperty("outside_max", sci(d.maxOutside));
  RecordProperty("outside_mean", sci(d.meanOutside));
  EXPECT_GT(d.outsideEdges, 0u);
  EXPECT_GT(d.maxInside, 0.05);  // the bend is strong enough to measure
  EXPECT_LE(d.maxOutside, 2.0 * d.maxInside);
  EXPECT_LE(d.meanOutside, 2.0 * d.meanInside);
  // No outside tet inverts.
  for (const Tet& t : bar.tets) EXPECT_GT(signedVolume(positions, t), 0.0);
  // The outside part keeps turning with the bend: its far end is rotated
  // about z by more than the angle at the cage boundary (20 / rho rad)
  // minus a tolerance, not left straight.
  const auto& basis = propagation.unknownTetBasis();
  double farAngle = 0;
  for (std::size_t k = 0; k < propagation.unknownTets().size(); ++k) {
    const Tet& t = bar.tets[std::size_t(propagation.unknownTets()[k])];
    if (bar.positions[std::size_t(t[0])].x() > 28.0) farAngle = std::max(farAngle, std::atan2(basis[k](1, 0), basis[k](0, 0)));
  }
  EXPECT_GT(farAngle, 0.7 * 20.0 / rho);
}

// The two ends of a bar inside, one fixed, the other turned 45 degrees about
// the bar's axis: the outside middle twists. Its transforms are rotations
// (a linear blend of the ends' would not be: half-way, (R + I) / 2 is a
// rotation by 22.5 degrees scaled by 0.92 across the axis), and no tet
// loses more than a fifth of its volume.
TEST(Propagation, TwistBetweenTwoRotationsPropagatesRotations) {
  const TetMesh bar = block(30, 6, 6);
  const Eigen::Vector3d axisPoint(0, 2.5, 2.5);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(std::numbers::pi / 4, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const auto inside = insideWhere(bar, [](const Eigen::Vector3d& p) { return p.x() < 6.0 || p.x() > 22.0; });
  std::vector<Eigen::Vector3d> positions(bar.vertexCount(), Eigen::Vector3d::Zero());
  for (std::size_t v = 0; v < bar.vertexCount(); ++v)
    if (inside[v]) positions[v] = bar.positions[v].x() < 6.0 ? bar.positions[v] : axisPoint + r * (bar.positions[v] - axisPoint);
  RigidityPropagation propagation;
  propagation.precompute(bar, inside);
  propagation.propagate(positions);
  for (const Eigen::Matrix3d& b : propagation.unknownTetBasis()) {
    EXPECT_LT((b.transpose() * b - Eigen::Matrix3d::Identity()).norm(), 1e-9);
    EXPECT_NEAR(b.determinant(), 1.0, 1e-9);
  }
  double restVolume = 0, volume = 0, smallest = std::numeric_limits<double>::infinity();
  for (const std::int32_t t : propagation.unknownTets()) {
    const Tet& tet = bar.tets[std::size_t(t)];
    const double before = signedVolume(bar.positions, tet), after = signedVolume(positions, tet);
    restVolume += before;
    volume += after;
    smallest = std::min(smallest, after / before);
  }
  RecordProperty("outside_volume_ratio", sci(volume / restVolume));
  RecordProperty("smallest_tet_volume_ratio", sci(smallest));
  EXPECT_NEAR(volume / restVolume, 1.0, 0.01);
  EXPECT_GT(smallest, 0.8);
}

TEST(DeformationMetrics, PolarRotation) {
  EXPECT_EQ(polarRotation(Eigen::Matrix3d::Identity()), Eigen::Matrix3d::Identity());
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 3).normalized()).toRotationMatrix();
  EXPECT_LT((polarRotation(r) - r).norm(), 1e-14);
  // Half-way between the identity and a rotation: the half rotation.
  const Eigen::Matrix3d half = Eigen::AngleAxisd(0.35, Eigen::Vector3d(1, -2, 3).normalized()).toRotationMatrix();
  EXPECT_LT((polarRotation(0.5 * (r + Eigen::Matrix3d::Identity())) - half).norm(), 1e-12);
  // B = R S with S symmetric positive definite gives R back.
  Eigen::Matrix3d s;
  s << 1.3, 0.2, -0.1, 0.2, 0.8, 0.3, -0.1, 0.3, 1.1;
  EXPECT_LT((polarRotation(r * s) - r).norm(), 1e-12);
  // A reflection or a degenerate matrix still gives a rotation.
  for (const Eigen::Matrix3d& b : {Eigen::Matrix3d(Eigen::Vector3d(1, 1, -1).asDiagonal()), Eigen::Matrix3d(Eigen::Vector3d(2, 1, 0).asDiagonal())}) {
    const Eigen::Matrix3d q = polarRotation(b);
    EXPECT_LT((q.transpose() * q - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    EXPECT_NEAR(q.determinant(), 1.0, 1e-12);
  }
}

TEST(Propagation, DetachedComponentFollowsItsNearestConstrainedTet) {
  const TetMesh a = block(10, 4, 4);
  const TetMesh b = block(4, 4, 4, {12.0, 0.0, 0.0});  // a separate component beside a
  const TetMesh both = concatenate(a, b);
  std::vector<std::uint8_t> inside(both.vertexCount(), 0);
  for (std::size_t v = 0; v < a.vertexCount(); ++v) inside[v] = a.positions[v].x() < 8.0 ? 1 : 0;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(-0.6, Eigen::Vector3d(0, 1, 1).normalized()).toRotationMatrix();
  const Eigen::Vector3d shift(1, 2, 3);
  std::vector<Eigen::Vector3d> positions(both.vertexCount(), Eigen::Vector3d::Zero());
  for (std::size_t v = 0; v < both.vertexCount(); ++v)
    if (inside[v]) positions[v] = r * both.positions[v] + shift;
  RigidityPropagation propagation;
  propagation.precompute(both, inside);
  EXPECT_EQ(propagation.diagnostics().unconstrainedTetGroups, 1u);
  EXPECT_EQ(propagation.diagnostics().unconstrainedVertexGroups, 1u);
  propagation.propagate(positions);
  double worst = 0;
  for (std::size_t v = 0; v < both.vertexCount(); ++v) worst = std::max(worst, (positions[v] - (r * both.positions[v] + shift)).norm());
  EXPECT_LT(worst, 1e-9 * 16.0);
}

TEST(Propagation, RejectsMissingConstraints) {
  const TetMesh bar = block(6, 3, 3);
  const std::vector<std::uint8_t> none(bar.vertexCount(), 0);
  RigidityPropagation propagation;
  try {
    propagation.precompute(bar, none);
    FAIL() << "no constraint accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("transfer mesh: no tet lies entirely inside the cage"), std::string::npos) << e.what();
  }
  const std::vector<std::uint8_t> wrongSize(3, 1);
  EXPECT_THROW(propagation.precompute(bar, wrongSize), InputError);
  TetMesh inverted = bar;
  std::swap(inverted.tets[5][0], inverted.tets[5][1]);
  const std::vector<std::uint8_t> all(bar.vertexCount(), 1);
  EXPECT_THROW(propagation.precompute(inverted, all), InputError);
}

TEST(DeformationMetrics, BasisChangeAndErrors) {
  const TetMesh bar = block(8, 4, 4);
  // Affine map: every B_t equals its matrix, every Delta B_t and e_t vanish.
  Eigen::Matrix3d m;
  m << 1.2, 0.3, 0.0, -0.1, 0.9, 0.2, 0.0, 0.1, 1.1;
  const Eigen::Vector3d shift(3, 4, 5);
  std::vector<Eigen::Vector3d> affine;
  for (const auto& p : bar.positions) affine.push_back(m * p + shift);
  for (const auto& b : basisChanges(bar, affine)) EXPECT_LT((b - m).norm(), 1e-12);
  const auto e = tetDeformationError(bar, affine);
  for (double x : e) EXPECT_LT(x, 1e-12);
  // A bend has a non-zero error that the vertex average reproduces on average.
  std::vector<Eigen::Vector3d> bent;
  for (const auto& p : bar.positions) bent.push_back(bend(p, 1.5, 6.0));
  const auto et = tetDeformationError(bar, bent);
  const auto ev = vertexDeformationError(bar, et);
  double maxT = 0, meanV = 0;
  for (double x : et) maxT = std::max(maxT, x);
  for (double x : ev) meanV += x / double(ev.size());
  EXPECT_GT(maxT, 1e-3);
  EXPECT_GT(meanV, 0.0);
  for (double x : ev) EXPECT_LE(x, maxT + 1e-15);
}

TEST(DeformationMetrics, DistortionHistograms) {
  const TetMesh bar = block(8, 4, 4);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  std::vector<Eigen::Vector3d> rigid;
  for (const auto& p : bar.positions) rigid.push_back(r * p);
  const DistortionHistograms h = distortionHistograms(bar, rigid);
  EXPECT_NEAR(h.volume, 8 * 4 * 4, 1e-9);
  EXPECT_NEAR(h.angle.min, 90.0, 1e-9);
  EXPECT_NEAR(h.angle.max, 90.0, 1e-9);
  EXPECT_NEAR(h.stretch.mean, 1.0, 1e-12);
  EXPECT_NEAR(h.angle.fractions[45], 1.0, 1e-12);  // bin [89.5, 90.5)
  EXPECT_NEAR(h.stretch.fractions[50], 1.0, 1e-12);  // bin [0.995, 1.005)
  // Shear x += 0.5 y: the (x, y) pair closes to atan2(1, 0.5) = 63.43 deg, the
  // y axis stretches by sqrt(1.25).
  std::vector<Eigen::Vector3d> sheared;
  for (const auto& p : bar.positions) sheared.push_back(p + Eigen::Vector3d(0.5 * p.y(), 0, 0));
  const DistortionHistograms s = distortionHistograms(bar, sheared);
  EXPECT_NEAR(s.angle.min, 63.4349488, 1e-6);
  EXPECT_NEAR(s.stretch.max, std::sqrt(1.25), 1e-12);
  double total = s.angle.below + s.angle.above;
  for (double f : s.angle.fractions) total += f;
  EXPECT_NEAR(total, 1.0, 1e-12);
  EXPECT_NEAR(s.angle.fractions[18], 1.0 / 3.0, 1e-12);  // bin [62.5, 63.5): one pair in three
}

}  // namespace
}  // namespace vox
