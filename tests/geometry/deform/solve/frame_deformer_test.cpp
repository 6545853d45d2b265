#include "tests/geometry/deform/cage_fixtures.h"
#include "geometry/deform/solve/frame_deformer.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/error.h"
#include "geometry/voxel_tetrahedralization.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cstdio>
#include <numeric>

namespace vox {
namespace {

std::string sci(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

struct Scene {
  TriMesh cage;
  TetMesh tm;
  std::vector<Eigen::Vector3d> envelope;
};

// TM: 20 x 6 x 6 unit voxels (x in [-0.5, 19.5]); cage: a box that stops at
// x = 15, so the end of the TM and of its surface lies outside the cage.
Scene scene() {
  Scene s;
  GridGeometry g;
  g.dims = {20, 6, 6};
  s.tm = tetrahedralizeVoxels(LabelGrid(g, 1), {.includeBackground = false});
  s.cage = test::subdividedBox({-2, -2, -2}, {15, 7.5, 7.5}, {6, 3, 3});
  // Envelope: the TM's boundary vertices.
  const auto nb = faceNeighbors(s.tm);
  std::vector<std::uint8_t> onBoundary(s.tm.vertexCount(), 0);
  for (std::size_t t = 0; t < s.tm.tetCount(); ++t)
    for (int k = 0; k < 4; ++k)
      if (nb[t][std::size_t(k)] < 0)
        for (std::int32_t v : tetFace(s.tm.tets[t], k)) onBoundary[std::size_t(v)] = 1;
  for (std::size_t v = 0; v < s.tm.vertexCount(); ++v)
    if (onBoundary[v]) s.envelope.push_back(s.tm.positions[v]);
  return s;
}

std::vector<std::int32_t> allVertices(const TriMesh& m) {
  std::vector<std::int32_t> v(m.vertexCount());
  std::iota(v.begin(), v.end(), 0);
  return v;
}

double worstRigidError(const std::vector<Eigen::Vector3d>& got, const std::vector<Eigen::Vector3d>& rest, const Eigen::Matrix3d& r,
                       const Eigen::Vector3d& shift) {
  double worst = 0;
  for (std::size_t v = 0; v < got.size(); ++v) worst = std::max(worst, (got[v] - (r * rest[v] + shift)).norm());
  return worst;
}

TEST(FrameDeformer, RigidCageMotionMovesEverythingRigidly) {
  const Scene s = scene();
  const auto handles = allVertices(s.cage);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.5, Eigen::Vector3d(0, 0, 1)).toRotationMatrix() *
                            Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 0, 0)).toRotationMatrix();
  const Eigen::Vector3d shift(100, -50, 20);
  Eigen::MatrixX3d targets(Eigen::Index(handles.size()), 3);
  for (std::size_t k = 0; k < handles.size(); ++k) targets.row(Eigen::Index(k)) = (r * s.cage.positions[k] + shift).transpose();
  const double size = 25.0;
  for (GreenPrecision precision : {GreenPrecision::Double, GreenPrecision::Float, GreenPrecision::Half}) {
    FrameDeformer deformer;
    deformer.precompute(s.cage, s.envelope, s.tm, handles, {.precision = precision});
    const FrameDeformerStats& stats = deformer.stats();
    EXPECT_GT(stats.transferMeshOutside, 0u);
    EXPECT_GT(stats.envelopeOutside, 0u);
    EXPECT_EQ(stats.transferMeshInside + stats.transferMeshOutside, s.tm.vertexCount());
    deformer.update(targets, 3);
    const double tmError = worstRigidError(deformer.transferMeshPositions(), s.tm.positions, r, shift) / size;
    const double envelopeError = worstRigidError(deformer.envelopePositions(), s.envelope, r, shift) / size;
    const std::string tag = precision == GreenPrecision::Double ? "double" : precision == GreenPrecision::Float ? "float" : "half";
    RecordProperty(tag + "_tm_relative_error", sci(tmError));
    RecordProperty(tag + "_envelope_relative_error", sci(envelopeError));
    const double tolerance = precision == GreenPrecision::Double ? 1e-9 : precision == GreenPrecision::Float ? 1e-6 : 1e-3;
    EXPECT_LT(tmError, tolerance);
    EXPECT_LT(envelopeError, tolerance);
    EXPECT_GE(deformer.timings().total, deformer.timings().arap);
  }
}

TEST(FrameDeformer, RestTargetsReproduceTheRestExactly) {
  const Scene s = scene();
  const auto handles = allVertices(s.cage);
  Eigen::MatrixX3d targets(Eigen::Index(handles.size()), 3);
  for (std::size_t k = 0; k < handles.size(); ++k) targets.row(Eigen::Index(k)) = s.cage.positions[k].transpose();
  FrameDeformer deformer;
  deformer.precompute(s.cage, s.envelope, s.tm, handles);  // float coordinates
  deformer.update(targets, 3);
  double worstOutside = 0;
  for (std::size_t v = 0; v < s.tm.vertexCount(); ++v) {
    if (deformer.transferMeshInside()[v]) {
      EXPECT_EQ(deformer.transferMeshPositions()[v], s.tm.positions[v]) << v;
    } else {
      worstOutside = std::max(worstOutside, (deformer.transferMeshPositions()[v] - s.tm.positions[v]).norm());
    }
  }
  for (std::size_t v = 0; v < s.envelope.size(); ++v) {
    if (deformer.envelopeInside()[v]) {
      EXPECT_EQ(deformer.envelopePositions()[v], s.envelope[v]) << v;
    }
  }
  // Outside: back-substitution through the normal equations.
  EXPECT_LT(worstOutside, 1e-10 * 25.0);
}

TEST(FrameDeformer, PoseDrivenBendKeepsTetsPositive) {
  const Scene s = scene();
  const Pose pose = parsePose(R"({"selections": [
      {"name": "base", "box": {"min": [-3, -3, -3], "max": [0, 8, 8]}, "fixed": true},
      {"name": "tip", "box": {"min": [14, -3, -3], "max": [16, 8, 8]},
       "transform": {"rotation": {"axis": [0, 0, 1], "angle_deg": 30, "center": [7, 2.75, 2.75]}}}]})",
                              "bend.json");
  const PoseHandles handles = selectHandles(pose, s.cage, "bend.json");
  FrameDeformer deformer;
  deformer.precompute(s.cage, s.envelope, s.tm, handles.vertices);
  // Animate the pose in steps, as the viewer does.
  for (double t : {0.25, 0.5, 0.75, 1.0}) deformer.update(handleTargets(pose, handles, s.cage, t), 5);
  for (const Tet& tet : s.tm.tets) EXPECT_GT(signedVolume(deformer.transferMeshPositions(), tet), 0.0);
  for (const auto& p : deformer.envelopePositions()) EXPECT_TRUE(p.allFinite());
  // The tip moved, the base did not.
  double tipMove = 0, baseMove = 0;
  for (std::size_t v = 0; v < s.tm.vertexCount(); ++v) {
    const double d = (deformer.transferMeshPositions()[v] - s.tm.positions[v]).norm();
    if (s.tm.positions[v].x() > 18) tipMove = std::max(tipMove, d);
    if (s.tm.positions[v].x() < 0) baseMove = std::max(baseMove, d);
  }
  RecordProperty("tip_move", sci(tipMove));
  RecordProperty("base_move", sci(baseMove));
  EXPECT_GT(tipMove, 3.0);
  EXPECT_LT(baseMove, 0.1 * tipMove);
}

TEST(FrameDeformer, RejectsOpenCage) {
  Scene s = scene();
  s.cage.triangles.pop_back();
  FrameDeformer deformer;
  EXPECT_THROW(deformer.precompute(s.cage, s.envelope, s.tm, allVertices(s.cage)), InputError);
}

}  // namespace
}  // namespace vox
