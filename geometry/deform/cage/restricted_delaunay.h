#pragma once
// Restricted Delaunay meshing (CGAL Mesh_3: Delaunay refinement after
// Boissonnat and Oudot) of domains sampled on a grid. One mesher serves the
// envelope and the cage (surfaces, thesis 3.2.2) and the transfer mesh
// (volume, thesis 3.2.4 / 4.2.2); CGAL stays in restricted_delaunay_cgal.cpp.
//
// Determinism: the mesher runs sequentially with fixed random seeds, so one
// input gives the same mesh, vertex for vertex, on every run.

#include "geometry/label_grid.h"
#include "geometry/scalar_grid.h"
#include "geometry/tet_mesh.h"
#include "geometry/tri_mesh.h"

#include <Eigen/Core>
#include <functional>

namespace vox {

// A labeled domain: labelAt(p) is the subdomain containing grid-frame point
// p (0 outside). `labels` holds labelAt at every voxel centre of its grid;
// it bounds the domain (labelAt must be 0 on its border voxels and beyond)
// and seeds every connected piece, so none is missed.
struct SampledDomain {
  const LabelGrid* labels = nullptr;
  std::function<int(const Eigen::Vector3d&)> labelAt;
};

struct SurfaceCriteria {
  double facetAngleDeg = 30.0;   // lower bound on the smallest facet angle
  double facetSizeMm = 6.0;      // upper bound on the radius of a facet's surface Delaunay ball
  double facetDistanceMm = 1.0;  // upper bound on the distance from a facet to the surface
};

// Boundary surface of the domain's foreground (every label > 0 counts as
// inside): closed, 2-manifold (Mesh_3's manifold mode), triangles
// counter-clockwise seen from outside.
TriMesh restrictedDelaunaySurface(const SampledDomain& domain, const SurfaceCriteria& criteria);

struct VolumeCriteria {
  double facetAngleDeg = 25.0;       // lower bound on boundary/interface facet angles
  double facetDistanceMm = 1.0;      // upper bound on boundary/interface facet to surface distance
  double radiusEdgeRatio = 3.0;      // upper bound on tet circumradius / shortest edge
  const ScalarGrid* sizing = nullptr;  // cell and facet size in mm, sampled at each point (required)
  // Also the Delaunay cells outside the domain, label 0, so that the tets
  // fill the convex hull as in Mesh_3's own triangulation (what CGAL's
  // tetrahedral remeshing takes as input).
  bool keepOutside = false;
  // Slivers (dihedral angle under 10 degrees) are exuded after refinement,
  // without a time limit so that the result does not depend on the machine;
  // false skips the exudation (a plain refined Mesh_3 mesh).
  bool exude = true;
};

// Tetrahedral mesh of the domain: tets carry their subdomain label (> 0, and
// 0 outside the domain with keepOutside),
// positively oriented, vertices unused by any tet dropped.
TetMesh restrictedDelaunayVolume(const SampledDomain& domain, const VolumeCriteria& criteria);

}  // namespace vox
