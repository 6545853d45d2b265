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
// with the lattice. Each lattice point's part (the first tet's) also gives
// the contacts: faces between neighbouring points of two parts, against the
// same faces of the rest body-part grid.

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

// Where two parts' tissue meets: the area of the faces between lattice
// points (or rest voxels) holding tissue of partA and of partB. What a pose
// adds beyond the rest's (posed - rest) is the contact the turn made: the
// back of the knee against the thigh, the arm against the chest.
struct ContactPair {
  Label partA = 0, partB = 0;  // partA < partB
  double restMm2 = 0.0, posedMm2 = 0.0;

  double newMm2() const { return posedMm2 - restMm2; }
};

struct Collisions {
  GridGeometry lattice;            // where they were counted
  std::int64_t bodyVoxels = 0;     // lattice points covered by tissue of some part
  std::int64_t voxels = 0;         // lattice points covered by tissue of two parts
  std::vector<CollisionPair> pairs;  // by decreasing voxels
  std::vector<ContactPair> contacts;  // every pair that meets at rest or posed, by decreasing newMm2()
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
