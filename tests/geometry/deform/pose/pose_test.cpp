#include "tests/geometry/deform/cage_fixtures.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/error.h"
#include "tests/support/test_environment.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <numbers>

namespace vox {
namespace {

// Cage: box [0, 100] x [0, 40] x [0, 200] mm split 4 x 2 x 8.
TriMesh boxCage() { return test::subdividedBox({0, 0, 0}, {100, 40, 200}, {4, 2, 8}); }

const char* kArmPose = R"({
  "name": "arm up",
  "arap_iterations": 7,
  "selections": [
    {"name": "everything", "box": {"min": [-1, -1, -1], "max": [101, 41, 201]}, "fixed": true},
    {"name": "right arm", "sphere": {"center": [100, 20, 200], "radius": 30},
     "transform": {"rotation": {"axis": [0, 2, 0], "angle_deg": 90, "center": [100, 20, 150]},
                   "translation": [0, 0, 10]}}
  ]
})";

std::string expectInputError(const std::string& text) {
  try {
    parsePose(text, "pose.json");
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "accepted: " << text;
  return "";
}

TEST(Pose, ParsesSelectsAndTransforms) {
  const Pose pose = parsePose(kArmPose, "pose.json");
  EXPECT_EQ(pose.name, "arm up");
  EXPECT_EQ(pose.arapIterations, 7);
  ASSERT_EQ(pose.selections.size(), 2u);
  EXPECT_TRUE(pose.selections[0].fixed);
  EXPECT_EQ(pose.selections[1].shape, SelectionShape::Sphere);
  EXPECT_NEAR(pose.selections[1].transform.axis.norm(), 1.0, 1e-15);

  const TriMesh cage = boxCage();
  const PoseHandles handles = selectHandles(pose, cage, "pose.json");
  // Every cage vertex is in the first box: all are handles; the later
  // sphere takes over the ones it holds.
  EXPECT_EQ(handles.vertices.size(), cage.vertexCount());
  std::size_t moving = 0;
  for (std::size_t k = 0; k < handles.vertices.size(); ++k) {
    const Eigen::Vector3d& p = cage.positions[std::size_t(handles.vertices[k])];
    const bool inSphere = (p - Eigen::Vector3d(100, 20, 200)).norm() <= 30.0;
    EXPECT_EQ(handles.selection[k], inSphere ? 1 : 0);
    moving += inSphere;
  }
  EXPECT_GT(moving, 0u);

  // The corner (100, 40, 200) rotates 90 degrees about +y around
  // (100, 20, 150): (x, z) offset (0, 50) -> (50, 0), then +10 in z.
  const Eigen::MatrixX3d full = handleTargets(pose, handles, cage, 1.0);
  const Eigen::MatrixX3d half = handleTargets(pose, handles, cage, 0.5);
  const Eigen::MatrixX3d none = handleTargets(pose, handles, cage, 0.0);
  for (std::size_t k = 0; k < handles.vertices.size(); ++k) {
    const Eigen::Vector3d& p = cage.positions[std::size_t(handles.vertices[k])];
    EXPECT_LT((none.row(Eigen::Index(k)).transpose() - p).norm(), 1e-12);
    if (handles.selection[k] == 0) {
      EXPECT_LT((full.row(Eigen::Index(k)).transpose() - p).norm(), 1e-12);
    }
    if ((p - Eigen::Vector3d(100, 40, 200)).norm() < 1e-9) {
      EXPECT_LT((full.row(Eigen::Index(k)).transpose() - Eigen::Vector3d(150, 40, 160)).norm(), 1e-9);
      // Half: 45 degrees and 5 mm.
      const double c = 50.0 * std::sqrt(0.5);
      EXPECT_LT((half.row(Eigen::Index(k)).transpose() - Eigen::Vector3d(100 + c, 40, 150 + c + 5)).norm(), 1e-9);
    }
  }
  EXPECT_THROW(handleTargets(pose, handles, cage, 1.5), InputError);
}

TEST(Pose, RoundTripsThroughAFile) {
  const Pose pose = parsePose(kArmPose, "pose.json");
  const std::string path = test::tempDir() + "/pose.json";
  writePose(path, pose);
  const Pose again = readPose(path);
  ASSERT_EQ(again.selections.size(), pose.selections.size());
  EXPECT_EQ(again.name, pose.name);
  EXPECT_EQ(again.arapIterations, pose.arapIterations);
  for (std::size_t k = 0; k < pose.selections.size(); ++k) {
    const auto& a = pose.selections[k];
    const auto& b = again.selections[k];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.shape, b.shape);
    EXPECT_EQ(a.fixed, b.fixed);
    EXPECT_EQ(a.boxMin, b.boxMin);
    EXPECT_EQ(a.boxMax, b.boxMax);
    EXPECT_EQ(a.center, b.center);
    EXPECT_EQ(a.radius, b.radius);
    EXPECT_EQ(a.transform.axis, b.transform.axis);
    EXPECT_EQ(a.transform.angleDeg, b.transform.angleDeg);
    EXPECT_EQ(a.transform.center, b.transform.center);
    EXPECT_EQ(a.transform.translation, b.transform.translation);
  }
}

TEST(Pose, SelectionThatSelectsNothingNamesItself) {
  const Pose pose = parsePose(R"({"selections": [
      {"name": "trunk", "box": {"min": [0, 0, 0], "max": [100, 40, 50]}, "fixed": true},
      {"name": "right arm", "sphere": {"center": [500, 500, 500], "radius": 10},
       "transform": {"translation": [0, 0, 5]}}]})",
                              "poses/arm.json");
  try {
    selectHandles(pose, boxCage(), "poses/arm.json");
    FAIL() << "an empty selection was accepted";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "poses/arm.json: selection 'right arm' selects no cage vertex");
  }
}

TEST(Pose, RejectsMalformedFiles) {
  EXPECT_NE(expectInputError("{").find("pose.json: invalid JSON"), std::string::npos);
  EXPECT_NE(expectInputError("[]").find("must be a JSON object"), std::string::npos);
  EXPECT_NE(expectInputError(R"({"name": "x"})").find("missing 'selections'"), std::string::npos);
  EXPECT_NE(expectInputError(R"({"selections": []})").find("non-empty"), std::string::npos);
  EXPECT_NE(expectInputError(R"({"selections": [{"box": {"min": [0,0,0], "max": [1,1,1]}}]})").find("exactly one of 'fixed'"),
            std::string::npos);
  EXPECT_NE(expectInputError(R"({"selections": [{"fixed": true}]})").find("exactly one of 'box', 'sphere' and 'points'"), std::string::npos);
  EXPECT_NE(expectInputError(R"({"selections": [{"name": "a", "box": {"min": [0,0,0], "max": [1,1]}, "fixed": true}]})")
                .find("selection 'a' box 'max' must be an array of 3 numbers"),
            std::string::npos);
  EXPECT_NE(expectInputError(R"({"selections": [{"box": {"min": [2,0,0], "max": [1,1,1]}, "fixed": true}]})").find("min > max"),
            std::string::npos);
  EXPECT_NE(expectInputError(R"({"selections": [{"sphere": {"center": [0,0,0], "radius": 0}, "fixed": true}]})").find("radius <= 0"),
            std::string::npos);
  EXPECT_NE(expectInputError(R"({"selections": [{"sphere": {"center": [0,0,0], "radius": 1},
            "transform": {"rotation": {"axis": [0,0,0], "angle_deg": 3, "center": [0,0,0]}}}]})")
                .find("zero rotation axis"),
            std::string::npos);
  EXPECT_NE(expectInputError(R"({"selections": [{"box": {"min": [0,0,0], "max": [1,1,1]}, "fixd": true}]})").find("unknown key 'fixd'"),
            std::string::npos);
  EXPECT_NE(expectInputError(R"({"arap_iterations": -1, "selections": [{"box": {"min": [0,0,0], "max": [1,1,1]}, "fixed": true}]})")
                .find("'arap_iterations'"),
            std::string::npos);
  EXPECT_NE(expectInputError(R"({"selections": [{"box": {"min": [0,0,0], "max": [1,1,1e999]}, "fixed": true}]})").find("pose.json:"),
            std::string::npos);
  EXPECT_THROW(readPose(test::tempDir() + "/missing.json"), InputError);
}

}  // namespace
}  // namespace vox
