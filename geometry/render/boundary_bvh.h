#pragma once
// Bounding-volume hierarchy over the boundary faces of a transfer mesh, used
// to find where camera rays enter the deformed mesh. The tree is built once
// from the rest positions; each frame only refits the boxes, since a
// deformation moves vertices but never changes which faces exist.

#include "geometry/tet_mesh.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace vox {

// A boundary face of the transfer mesh: vertices (indices into the TM
// positions) ordered so the normal (b - a) x (c - a) points out of the rest
// mesh, and the tet it bounds.
struct BoundaryFace {
  Tri vertices;
  std::int32_t tet = -1;
};

// Depth-first node order. Inner node: children are node + 1 and `right`,
// count == 0. Leaf: faces [first, first + count) of the face array.
struct BvhNode {
  Eigen::Vector3d lo, hi;
  std::int32_t rightOrFirst = 0;
  std::int32_t count = 0;
};

inline constexpr int kBvhLeafFaces = 4;
inline constexpr int kBvhMaxDepth = 32;  // traversal stacks hold 2 * kBvhMaxDepth nodes

// Builds the tree over `faces` (reordering them into leaf order) with boxes
// for `positions` (#V). Median splits along the longest axis of the face
// centroids.
std::vector<BvhNode> buildBoundaryBvh(std::vector<BoundaryFace>& faces, const std::vector<Eigen::Vector3d>& positions);

// Recomputes every box bottom-up for new positions. The GPU ray caster refits
// its own copy (shaders/raycast_refit.comp); this is its reference.
void refitBoundaryBvh(std::vector<BvhNode>& nodes, const std::vector<BoundaryFace>& faces,
                      const std::vector<Eigen::Vector3d>& positions);

// Ray / boundary-face intersection keyed by (t, face index): hits are ordered
// by t, ties by face index, so "the next entry after a hit" is well defined.
struct FaceHit {
  double t = 0.0;
  std::int32_t face = -1;  // index into the face array; -1 = no hit
  bool valid() const { return face >= 0; }
};

// Barycentric tolerance of the ray / triangle test: rays through a shared
// edge hit both faces, never neither.
inline constexpr double kFaceHitTolerance = 1e-4;

// The front-facing face (the ray enters the mesh through it: d . n < 0) hit
// at the smallest key (t, face) greater than (afterT, afterFace).
FaceHit firstEntryAfter(const std::vector<BvhNode>& nodes, const std::vector<BoundaryFace>& faces,
                        const std::vector<Eigen::Vector3d>& positions, const Eigen::Vector3d& origin,
                        const Eigen::Vector3d& direction, double afterT, std::int32_t afterFace);

}  // namespace vox
