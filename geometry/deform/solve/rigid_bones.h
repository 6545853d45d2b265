#pragma once
// Rigid bones: the transfer-mesh (TM) tets that hold bone voxels of one body
// part move with one rigid motion per frame, whatever the cage and the
// propagation do around them.
//
//  - Bone keys: each bone voxel of the working grid gets the key
//    part * kBoneKeyStride + bone (skeleton::Part, skeleton::Bone), from the
//    organ table's bone names and the body-part grid; 0 elsewhere.
//  - Groups: the rest TM is scan-converted onto the grid (lattice_tets.h,
//    each voxel centre to the lowest-index tet that holds it); a tet that
//    holds bone voxels of part P puts its four vertices in P's group. A
//    vertex whose tets hold bones of two parts (the tissue of a joint
//    between two bones) belongs to neither and is placed as before.
//  - Per frame (FrameDeformer): each group's rigid motion is the
//    least-squares fit (the rotation of the polar decomposition of the
//    cross-covariance, svdRotation) to the Green-coordinate positions of its
//    vertices inside the cage; every vertex of the group is then put at its
//    rest position moved by that motion, and the propagation takes the
//    group's vertices as known, like those inside the cage.
// A tet whose four vertices are in one group moves rigidly: its bone voxels
// keep their shape exactly. The report measures what is left (tets at the
// joints with a shared vertex): per bone, the largest |ln(l'/l)| over the
// edges of the tets holding it and its volume through the TM's Jacobians.

#include "geometry/label_grid.h"
#include "geometry/organ_table.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <span>
#include <vector>

namespace vox {

inline constexpr Label kBoneKeyStride = 32;

// Per voxel of `grid`: part * kBoneKeyStride + bone for a bone voxel (its
// label's name classifies as a bone, bones.h) of a body part (`parts`, same
// dims), 0 elsewhere.
LabelGrid boneKeyGrid(const LabelGrid& grid, const OrganTable& organs, const LabelGrid& parts);

struct RigidBoneGroups {
  // Per TM vertex: its group (index into groupPart), or -1.
  std::vector<std::int32_t> vertexGroup;
  std::vector<Label> groupPart;  // per group: the body part (skeleton::Part value)
  // Bone voxels held by each tet, per bone key (sorted by tet, then key).
  struct TetVoxels {
    std::int32_t tet = 0;
    Label key = 0;
    std::int32_t voxels = 0;
  };
  std::vector<TetVoxels> tetVoxels;
  std::size_t sharedVertices = 0;    // near tets holding bones of two parts: in no group
  std::int64_t uncoveredVoxels = 0;  // bone voxels in no tet
  double voxelVolume = 0.0;          // mm^3
  bool empty() const { return groupPart.empty(); }
};

// The groups of `rest` (grid frame mm, the TM at rest) on the lattice of
// `boneKeys` (boneKeyGrid). The vertices within `jointRings` tet rings of a
// shared vertex are left out of the groups too (sharedVertices counts them).
RigidBoneGroups rigidBoneGroups(const TetMesh& rest, const LabelGrid& boneKeys, int jointRings = 2);

// The per-frame fit: precompute() once per TM, apply() after the Green
// coordinates placed the vertices inside the cage.
class RigidBoneFit {
public:
  // vertexGroup: per TM vertex, a group or -1. fitted: per TM vertex, 1
  // when its frame position comes from the Green coordinates (the fit's
  // data). A group with fewer than 4 such vertices cannot be fitted: its
  // vertices are left out (ungrouped()).
  void precompute(std::span<const std::int32_t> vertexGroup, std::span<const std::uint8_t> fitted,
                  std::span<const Eigen::Vector3d> rest);
  // Moves every group vertex rigidly: with motions[group] when given (one
  // per group id), else with the group's fit to `positions`.
  void apply(std::span<Eigen::Vector3d> positions, std::span<const Eigen::Isometry3d> motions = {}) const;
  // Per TM vertex: 1 when apply() places it.
  const std::vector<std::uint8_t>& placed() const { return placed_; }
  std::size_t groups() const { return groups_.size(); }
  std::size_t droppedGroups() const { return dropped_; }

private:
  struct Group {
    std::int32_t id = 0;
    std::vector<std::int32_t> sources, members;
    Eigen::Vector3d restCentroid = Eigen::Vector3d::Zero();
  };
  std::vector<Group> groups_;
  std::vector<Eigen::Vector3d> rest_;
  std::vector<std::uint8_t> placed_;
  std::size_t dropped_ = 0;
};

// Per bone key of `groups`: how rigidly the TM moved it.
struct BoneRigidity {
  Label key = 0;  // part * kBoneKeyStride + bone
  std::int64_t voxels = 0;          // bone voxels in tets
  std::size_t tets = 0, vertices = 0, rigidVertices = 0, edges = 0;
  double maxStrain = 0.0;           // largest |ln(l'/l)| over the edges of its tets
  double restVolumeMm3 = 0.0, posedVolumeMm3 = 0.0;  // voxels x voxel volume, and through det(B_t)
  double volumeChangePercent() const { return restVolumeMm3 > 0 ? 100.0 * (posedVolumeMm3 / restVolumeMm3 - 1.0) : 0.0; }
};
std::vector<BoneRigidity> measureBoneRigidity(const RigidBoneGroups& groups, const TetMesh& rest,
                                              std::span<const Eigen::Vector3d> deformed);

}  // namespace vox
