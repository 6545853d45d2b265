#pragma once
// Envelope (thesis 3.2.2): a smooth triangle surface of the foreground of a
// label grid, the visual feedback deformed by Green coordinates each frame.
// The binary grid B (label != 0) is smoothed by a Gaussian, and the 1/2
// level set of its trilinear interpolation is meshed by restricted Delaunay
// refinement (CGAL Mesh_3 in manifold mode).

#include "geometry/label_grid.h"
#include "geometry/tri_mesh.h"

namespace vox {

struct EnvelopeOptions {
  double smoothingMm = 2.0;       // Gaussian sigma on B (mm): removes the voxel stairs of the finest axes
  double facetSizeMm = 8.0;       // upper bound on facet (surface Delaunay ball) radius: ~27k vertices on a body
  double facetDistanceMm = 1.0;   // upper bound on the facet-to-level-set distance
  double facetAngleDeg = 30.0;    // lower bound on facet angles (30 is Mesh_3's termination bound)
};

// Closed 2-manifold surface (several components if the foreground has
// several), triangles counter-clockwise seen from outside, grid frame mm.
// Throws InputError("grid", ...) for a grid without foreground.
TriMesh extractEnvelope(const LabelGrid& grid, const EnvelopeOptions& options = {});

}  // namespace vox
