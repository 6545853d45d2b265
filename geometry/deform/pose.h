#pragma once
// Pose files: which cage vertices are handles and where they go, as data.
//
// JSON schema (docs/POSES.md has the full description and examples):
//   {
//     "name": "right arm raised",                      optional string
//     "arap_iterations": 10,                           optional integer >= 0
//     "selections": [                                  required, non-empty
//       { "name": "trunk",                             optional string
//         "box": {"min": [x, y, z], "max": [x, y, z]}, exactly one of box / sphere
//         "fixed": true },                             exactly one of fixed / transform
//       { "name": "right arm",
//         "sphere": {"center": [x, y, z], "radius": r},
//         "transform": {
//           "rotation": {"axis": [x, y, z], "angle_deg": a, "center": [x, y, z]},   optional
//           "translation": [x, y, z] } }                                              optional
//     ]
//   }
// Coordinates are millimetres in the grid frame (origin + spacing .* ijk is
// the centre of voxel ijk), so a pose survives regenerating the cage.
// A selection takes the cage vertices inside its box (bounds included) or
// sphere (distance <= radius). A transform maps x to
//   R(axis, angle) (x - center) + center + translation.
// Selections apply in file order and a vertex selected more than once
// belongs to the LAST selection that selects it (so "fix everything, then
// move the arm" is written as two selections).
// Errors name the file: unreadable file, invalid JSON, unknown or missing
// keys, wrong types, non-finite numbers, an empty box, a radius <= 0, a zero
// rotation axis, and a selection that selects no cage vertex:
//   "<path>: selection 'right arm' selects no cage vertex".

#include "geometry/tri_mesh.h"

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace vox {

struct PoseTransform {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit length
  double angleDeg = 0.0;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  // The transform applied partially: angle and translation scaled by
  // `fraction` in [0, 1] (0: identity, 1: the full transform).
  Eigen::Vector3d apply(const Eigen::Vector3d& x, double fraction = 1.0) const;
};

enum class SelectionShape { Box, Sphere };

struct PoseSelection {
  std::string name;
  SelectionShape shape = SelectionShape::Box;
  Eigen::Vector3d boxMin = Eigen::Vector3d::Zero();
  Eigen::Vector3d boxMax = Eigen::Vector3d::Zero();
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // sphere
  double radius = 0.0;                               // sphere
  bool fixed = false;                                // else `transform` moves it
  PoseTransform transform;

  bool contains(const Eigen::Vector3d& p) const;
};

struct Pose {
  std::string name;
  std::vector<PoseSelection> selections;
  int arapIterations = 10;
};

// Throws InputError(source, ...) on any fault listed above.
Pose parsePose(const std::string& jsonText, const std::string& source);
Pose readPose(const std::string& path);
// Serializes with the same schema (readPose(writePose(p)) == p); atomic write.
std::string poseToJson(const Pose& pose);
void writePose(const std::string& path, const Pose& pose);

// The ARAP handle set a pose induces on a cage.
struct PoseHandles {
  std::vector<std::int32_t> vertices;   // cage vertex ids, increasing
  std::vector<std::int32_t> selection;  // per handle: the selection (index into Pose::selections) that owns it
};

// Throws InputError(source, "selection '<name>' selects no cage vertex") for
// a selection whose box or sphere holds no cage vertex (before later
// selections take any of them over).
PoseHandles selectHandles(const Pose& pose, const TriMesh& cage, const std::string& source);

// Targets of the handles (#handles by 3, rows in handles.vertices order) for
// the pose applied by `fraction` in [0, 1]: fixed handles stay at their rest
// position, the others get their selection's transform scaled by fraction.
Eigen::MatrixX3d handleTargets(const Pose& pose, const PoseHandles& handles, const TriMesh& cage, double fraction = 1.0);

}  // namespace vox
