#pragma once
// Automatic cage (thesis 3.2.2 and 4.2.1): the foreground of the label-group
// grid S is dilated by a distance in mm, the boundary of the dilated set is
// meshed by restricted Delaunay refinement, and the surface is simplified by
// QEM (Garland-Heckbert) to a few hundred vertices.
//
// Limb separation (4.2.1, Figure 4.2): for each requested pair of groups,
// the voxels of either group within `erosionMm` of the other (inside an
// optional region) are eroded, and inside the region the dilation radius
// shrinks with the distance to the other group, so the inset cage passes
// between the two limbs whether they touch or are merely close. The eroded voxels,
// and whatever QEM cuts off, end up outside the cage: the outliers that the
// propagation solve (4.2.2) places.

#include "geometry/deform/cage/surface_checks.h"
#include "geometry/label_grid.h"
#include "geometry/tri_mesh.h"

#include <Eigen/Geometry>
#include <optional>
#include <vector>

namespace vox {

struct LimbSeparation {
  Label groupA = 0, groupB = 0;               // values of S to separate (e.g. LabelGroup::RightArm, LabelGroup::Trunk)
  std::optional<Eigen::AlignedBox3d> region;  // grid frame mm; the whole grid when empty
};

struct CageOptions {
  double dilationMm = 20.0;       // offset of the cage from the foreground's voxel centres
  int targetVertices = 300;       // QEM stops at this many vertices
  double facetSizeMm = 20.0;      // resolution of the dilated boundary before QEM (~7k vertices on a body)
  double facetDistanceMm = 2.0;   // its distance bound
  double erosionMm = 10.0;        // limb separation: depth eroded on each side of an interface
  // Limb separation: inside a region, a voxel of one group is dilated by at
  // most this factor times its distance to the other group (below 1/2 the
  // dilated groups cannot meet), so the gap opens as a wedge.
  double separationSlope = 0.3;
  std::vector<LimbSeparation> separations;
};

struct CageReport {
  std::size_t meshedVertices = 0;      // dilated boundary before QEM
  std::int64_t erodedVoxels = 0;       // limb separation: voxels removed at the interfaces
  std::int64_t foregroundOutside = 0;  // foreground voxel centres outside the final cage
  SurfaceCheck check;                  // of the final cage
};

struct CageResult {
  TriMesh cage;  // outward oriented, grid frame mm
  CageReport report;
};

// Builds the cage of S's foreground (any label grid works: label != 0 is
// foreground; separations refer to S's values). Throws InputError("grid",
// ...) for a grid without foreground or a separation naming a group that
// has no voxels. The cage's validity is reported, not enforced: see
// report.check.validCage().
CageResult buildCage(const LabelGrid& groups, const CageOptions& options = {});

// QEM edge collapse (Garland-Heckbert plane quadrics, optimal placement,
// collapses that flip a face normal rejected) down to `targetVertices`;
// the link condition keeps the topology, so a closed manifold stays one.
TriMesh simplifyQem(const TriMesh& surface, int targetVertices);

}  // namespace vox
