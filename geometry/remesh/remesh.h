#pragma once
// M-MAd: multi-material isotropic remeshing of a labeled tet mesh with exact
// preservation of every label's topology and of every 1- and 0-junction
// (thesis chapter 2). The main loop reads like the paper (2.2.1):
//
//   repeat `iterations` times:  split long edges, collapse short edges,
//                               flip edges, smooth vertices
//   repeat `flipSmoothCycles`:  flip edges, smooth vertices
//   polish the vertices of the worst tets
//   insert Steiner points at the tets still poor; if any: flip, polish and
//   insert once more
//   insert Steiner points at the tets still poor
//
// with e_max = 4/3 l and e_min = 4/5 l for the target length l, uniform or
// the sizing field's at each edge's mid-point.

#include "geometry/remesh/feature_edges.h"
#include "geometry/remesh/flip_edges.h"
#include "geometry/remesh/insert_steiner_points.h"
#include "geometry/remesh/remesh_complex.h"
#include "geometry/remesh/sizing_field.h"
#include "geometry/tet_mesh.h"

#include <cstddef>
#include <string>
#include <vector>

namespace vox::remesh {

struct RemeshOptions {
  double targetLength = 0.0;   // l in mm (required, > 0); l_B with a sizing field
  // Adaptive target lengths (thesis 2.3.7, eq. 2.2) in the complex's frame;
  // null: the uniform targetLength. Not owned.
  const SizingField* sizing = nullptr;
  // Split-collapse-flip-smooth rounds. The thesis uses 5 (+ 2-3 flip-smooth
  // cycles) in its examples and calls 5-10 typical; 10 were measured to add
  // no quality worth their time (docs/BENCHMARKS.md, "Rounds against quality").
  int iterations = 5;
  int flipSmoothCycles = 3;    // final flip-smooth rounds
  // Width of the point set surfaces' Gaussian (mm); 0 picks the larger of
  // l / 2 and the mean length of the input's boundary edges.
  double mlsRadius = 0.0;
  bool projectOnInterfaces = true;  // project boundary vertices onto the PSS/MLS models
  // Hermite point set surfaces (HPSS) instead of plain PSS: measured to keep
  // label volumes far better on voxel input (docs/REMESH.md).
  bool hermite = true;
  int threads = 2;
  // The interfaces' Hausdorff bound, in units of l (l_B with a sizing
  // field): a collapse, a smoothing or polish move of an interface vertex
  // and a flip of an interface edge for the valences are made only when the
  // interface facets they make stay within it of the input's interface of
  // the same labels, and the input's within it of them (interface_bound.h;
  // MMG3D's -hausd). The acceptance asks 0.5 l of the report's sampled
  // distance; the flips that remove a sliver and the Steiner points still
  // move the interfaces a little. 0: no bound.
  double hausdorff = 0.45;
  FlipOptions flip;
  // After the last round, the vertices of tets with a dihedral angle under
  // this (degrees) are moved to lift the smallest angle (polishWorstTets,
  // smooth_vertices.h); 0 skips it.
  double polishAngle = 12.0;
  // Then edges of the domain tets still under steiner.angle are split where
  // a new vertex lifts their worst angle (insertSteinerPoints); angle 0
  // skips it.
  SteinerOptions steiner;
  // Tagged features (thesis 2.3.8, feature_edges.h), tagged by remeshTetMesh
  // before the first round: with sharpFeatures, the creases of the outer
  // boundary where the facets' normals differ by more than featureAngle
  // (degrees; the thesis gives no value, 60 is the usual choice of mesh
  // generators' crease detection); and the user's polylines (mm, not owned),
  // snapped within targetLength of the mesh, `featureSource` naming them in
  // errors. Points where a line turns by more than featureAngle are corners.
  bool sharpFeatures = false;
  double featureAngle = 60.0;
  const std::vector<FeatureSegment>* featureSegments = nullptr;
  std::string featureSource = "features";
};

struct RemeshStep {
  std::string name;  // "iteration 3", "flip-smooth 1"
  std::size_t splits = 0, collapses = 0, surfaceFlips = 0, innerFlips = 0, faceFlips = 0;
  std::size_t smoothedFeature = 0, smoothedSurface = 0, smoothedInside = 0;
  std::size_t tets = 0;  // live tets of the extended complex afterwards
  double splitSeconds = 0.0, collapseSeconds = 0.0, flipSeconds = 0.0, smoothSeconds = 0.0;
  double seconds = 0.0;
};

struct RemeshStats {
  std::vector<RemeshStep> steps;
  // Tagged before the first round: lines, edges, and the lines' input
  // geometry (the creases' edges, the user's polylines as given).
  std::size_t featureLines = 0, featureEdges = 0;
  std::vector<FeatureSegment> featureInput;
  std::size_t polished = 0;  // vertices the polish moved (both polishes)
  double polishSeconds = 0.0;  // the first polish
  std::size_t inserted = 0;     // Steiner points
  std::size_t sliverFlips = 0;  // flips of the round after the first insertion
  double insertSeconds = 0.0;   // insertion and the round after it
  double seconds = 0.0;
};

// Remeshes the extended complex in place. Throws InputError("remesh", ...)
// for a target length that is not positive and finite.
void remeshComplex(RemeshComplex& complex, const RemeshOptions& options, RemeshStats* stats = nullptr);

// Tags the features the options ask for on `complex` (see RemeshOptions).
void tagFeatures(RemeshComplex& complex, const RemeshOptions& options, RemeshStats* stats = nullptr);

// The extended complex of `mesh` (see RemeshComplex), its features tagged,
// remeshed; returns its domain tets, plus the geometric imaginary tets with
// keepImaginary, and in `features` the tagged edges in its numbering.
TetMesh remeshTetMesh(const TetMesh& mesh, const RemeshOptions& options, RemeshStats* stats = nullptr,
                      bool keepImaginary = false, const std::string& source = "mesh",
                      std::vector<TaggedEdge>* features = nullptr);

}  // namespace vox::remesh
