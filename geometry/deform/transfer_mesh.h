#pragma once
// Transfer mesh (thesis 3.2.4 and 4.2.2): an adaptive Delaunay tetrahedral
// mesh of the foreground (CGAL Mesh_3) whose tet size follows a sizing-field
// grid F, multi-material from the label-group grid S so that each tet
// carries its body-part group; and the cutting that separates two groups
// inside a region by duplicating the vertices of their shared faces
// (Figure 4.3).

#include "geometry/label_grid.h"
#include "geometry/scalar_grid.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Geometry>
#include <functional>
#include <optional>
#include <span>
#include <vector>

namespace vox {

// Lengths tied to voxel coverage are in units of the grid's finest spacing
// (2.137 mm on the ICRP adult male).
struct TransferMeshOptions {
  // The mesh's boundary is the level set at this distance from the
  // foreground's voxel centres, so every foreground voxel centre lies in a
  // tet (the rasterizer needs that) while the volume stays within a few %
  // of the voxels' volume on a body. Where Delaunay facets still cut a
  // centre off (sharp convex features), a cap covers it (coverageCaps);
  // for the centres no cap covers, the offset is raised locally and the
  // mesh rebuilt, at most three times.
  double boundaryOffsetVoxels = 1.4;
  // Caps (capUncoveredVoxels) before any rebuild: one tet on the boundary
  // facet beyond which a centre lies, where that tet meets no other part of
  // the mesh. false: every uncovered centre rebuilds the mesh.
  bool coverageCaps = true;
  double facetDistanceVoxels = 0.5;  // upper bound on boundary/interface facet to surface distance
  double facetAngleDeg = 25.0;   // lower bound on boundary/interface facet angles
  double radiusEdgeRatio = 3.0;  // upper bound on tet circumradius / shortest edge
};

// The thesis' initial F: constant, `fraction` of the grid's diagonal, on
// the grid's own geometry.
ScalarGrid defaultSizingField(const GridGeometry& geometry, double fraction = 0.05);

// Transfer mesh of S (`groups`: 0 background, > 0 group; B for a single
// material, see binaryGroupGrid). Tet and boundary facet sizes follow
// `sizing` (mm, sampled at each point; any geometry covering the grid).
// Tets carry their group (> 0), are positively oriented, grid frame mm;
// the result is the same on every run. Throws InputError("grid", ...) for a
// grid without foreground or a sizing field with non-positive values.
// `relabel`, when given, takes each foreground point's group and returns the
// label the mesher resolves there (> 0): analytic interfaces, such as a
// joint's articular sphere, that the grid's voxels would only staircase;
// it is called from the parallel loop's threads at once.
// `uncoveredVoxels`, when given, receives countUncoveredVoxels(mesh, groups),
// which the coverage repair has counted already (cutTransferMesh leaves it
// unchanged: it copies positions).
using TransferMeshRelabel = std::function<int(const Eigen::Vector3d& p, int group)>;
TetMesh buildTransferMesh(const LabelGrid& groups, const ScalarGrid& sizing, const TransferMeshOptions& options = {},
                          const TransferMeshRelabel& relabel = {}, std::int64_t* uncoveredVoxels = nullptr);

// Foreground voxels (label != 0) of `grid` whose centres lie in no tet.
std::int64_t countUncoveredVoxels(const TetMesh& mesh, const LabelGrid& grid);

// Covers the voxel centres `uncovered` (linear indices of `grid`, each
// outside `mesh`) by caps: for a centre at most 2.5 voxels beyond a
// boundary facet (one that the centre projects into), a tet on that facet
// whose apex lies beyond the centre, the best shaped of a few, added when
// it meets no other boundary facet (so no two tets overlap) and labelled as
// the facet's tet. The facets of tets labelled as the centre's voxel in
// `grid` are tried first, nearest first, then the others; a cap covers the
// later centres it holds too. Returns the centres no cap covers.
std::vector<std::int64_t> capUncoveredVoxels(TetMesh& mesh, const LabelGrid& grid, std::span<const std::int64_t> uncovered);

struct CutReport {
  std::size_t cutFaces = 0;            // faces between a groupA and a groupB tet inside the region
  std::size_t duplicatedVertices = 0;  // vertices added
  std::size_t openedRimFaces = 0;      // other faces opened where the cut meets the region's rim
  std::size_t contactVertices = 0;     // vertices where the groups meet without a shared face, split too
  // The vertices on either side of the cut: each split vertex and its copies, ascending.
  std::vector<std::int32_t> splitVertices;
};

// Cuts `mesh` between tets of groupA and groupB (thesis 4.2.2): every face
// they share whose centroid lies in `region` (all of them when empty) is
// opened. Each vertex of such faces gets one duplicate per fan of groupB
// tets around it (groupB tets joined through groupB-groupB faces at that
// vertex) that touches a cut face, and those groupB tets are re-indexed on
// it; groupA and other tets keep the original. Positions are copied, so
// volumes and orientations are unchanged. Where the cut meets the region's
// rim, faces between the re-indexed groupB tets and other tets at those
// vertices open too (reported): no tet stays face-connected across the cut.
// Vertices in the region where groupA and groupB tets meet through an edge
// or the vertex alone are split the same way (every groupB fan gets a copy),
// so no tet stays vertex-connected across the cut either.
CutReport cutTransferMesh(TetMesh& mesh, std::int32_t groupA, std::int32_t groupB,
                          const std::optional<Eigen::AlignedBox3d>& region = std::nullopt);

// The same cut between two sets of tet labels inside any region: the faces
// between a sideB and a sideA tet whose centroid is in the region (all of
// them without inRegion) open, and sideB tets take the copies (a joint's
// articular body against the tissue around it, articulated_mesh.h).
struct CutSides {
  std::function<bool(std::int32_t label)> sideA, sideB;
  std::function<bool(const Eigen::Vector3d& p)> inRegion;
};
CutReport cutTransferMesh(TetMesh& mesh, const CutSides& sides);

}  // namespace vox
