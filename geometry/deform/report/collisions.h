#pragma once
// Collisions of a posed body: points of the output lattice that deformed
// transfer-mesh (TM) tets cover with body tissue of two different body parts
// (a hand pressed into the head, a thigh into the belly). The rasterizer
// gives such a point to the lowest-index tet (rasterize.h) and so hides the
// overlap; this pass finds it.
//
// Every lattice point inside a deformed tet is mapped back through the tet's
// affine map to its rest position, whose voxel in the body-part grid names
// the part (background maps to nothing). A point that two tets map to
// tissue of two different parts collides. The lattice is processed slice by
// slice (lattice_tets.h scan conversion), so only the optional mask grows
// with the lattice. Each lattice point's part and rest position (the first
// tet's) also give the contacts (ContactPair).

#include "geometry/label_grid.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace vox {

struct CollisionPair {
  Label partA = 0, partB = 0;  // partA < partB (skeleton::Part values)
  std::int64_t voxels = 0;
};

// Where tissue of two parts that lay apart at rest meets in the pose: the
// area of the faces between neighbouring lattice points of partA and partB
// whose rest positions (through their tets' maps) are more than two rest
// voxels apart (the back of the knee against the thigh, the arm against the
// chest). A joint's own interface, whose points were neighbours at rest,
// does not count, however it turned.
struct ContactPair {
  Label partA = 0, partB = 0;  // partA < partB
  double areaMm2 = 0.0;
};

struct Collisions {
  GridGeometry lattice;            // where they were counted
  std::int64_t bodyVoxels = 0;     // lattice points covered by tissue of some part
  std::int64_t voxels = 0;         // lattice points covered by tissue of two parts
  std::vector<CollisionPair> pairs;  // by decreasing voxels
  std::vector<ContactPair> contacts;  // by decreasing area
  // With keepMask: 1 at colliding points, 0 elsewhere (the lattice's geometry).
  LabelGrid mask;

  double volumeMm3() const { return double(voxels) * lattice.voxelVolume(); }
  double bodyFraction() const { return bodyVoxels > 0 ? double(voxels) / double(bodyVoxels) : 0.0; }
};

// rest: the TM at rest (grid frame); deformed: its posed positions; parts:
// the body-part grid at rest (same frame as rest); lattice: the points to
// test (e.g. the posed grid, rasterize.h deformedGridGeometry).
Collisions findCollisions(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed, const LabelGrid& parts,
                          const GridGeometry& lattice, bool keepMask = false, int threads = 0);

}  // namespace vox
