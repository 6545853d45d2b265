#pragma once
// Deformation-adaptive refinement of the transfer mesh (thesis 4.2.2,
// eq. 4.5-4.6). The TM linearizes the deformation tet by tet; where the
// basis change B_t varies between neighbouring tets the linearization errs:
//   e_t = ||Delta B_t||                                     (eq. 4.5)
//   e_v = volume-weighted mean of e_t around v              (eq. 4.6)
//   e_g = e_v interpolated onto the grid through the rest TM
// The thesis regenerates the whole TM under a sizing field shrunk where e_g
// is large (eq. 4.7), then embeds and deforms all of it again. Here the TM
// is refined in place instead: each round splits only the tets whose e_t
// crosses the threshold that makes the error non-uniform (e_t > uniformRatio
// e_mean), by three successive bisections (about the edge halving of a
// regular 1-to-8 subdivision), and only the new midpoints are embedded (the
// subject places them by the deformation itself; a midpoint with an end
// placed otherwise, by the propagation outside the cage or a rigid bone,
// stays on its edge's image). A tet with fewer than two vertices the
// deformation places is not marked: no split could change its B_t.
//
// Every tet is bisected by its own longest edge (Rivara's longest-edge
// propagation path: when a neighbour on a marked tet's longest edge has a
// longer one, that neighbour is split first). Bisecting other edges makes
// slivers, within one round of three bisections, and on a sliver B_t
// magnifies the small difference between the Green coordinates of a
// midpoint and its tet's affine map into a large, spurious distortion.
//
// Edge bisection keeps the mesh conforming (every tet on the edge is split
// at the same midpoint), the tets positively oriented (each child keeps its
// parent's orientation, half its volume) and the union of the tets, so the
// voxels the TM covers stay covered.
//
// Stopping, checked before each round:
//  - negligible: max e_g <= negligibleError (a rigid or identity pose);
//  - uniform: max e_g <= uniformRatio * e_mean;
//  - stalled: max e_g fell by less than minImprovement in the last round;
//  - iterations: maxIterations rounds done;
//  - tet budget: no marked tet's split fits maxTets;
//  - unsplittable: no tet above the threshold has two vertices the
//    deformation places.
// The loop then keeps the TM of the lowest max e_g it measured: a round that
// made the error worse is undone.

#include "geometry/raster/field_interpolation.h"
#include "geometry/scalar_grid.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace vox {

struct RefinementOptions {
  int maxIterations = 3;            // splitting rounds at most (0: measure the error only)
  std::int64_t maxTets = 250000;    // tet budget of the refined TM
  double uniformRatio = 4.0;        // uniform when max e_g <= uniformRatio * e_mean; tets above split
  double negligibleError = 1e-3;    // ||Delta B|| below this changes no voxel (1e-3 of a tet's size)
  double minImprovement = 0.1;      // stalled when max e_g drops by less than this fraction
};

// The grid error e_g of a deformed TM on `geometry` (eq. 4.5-4.6 and the
// interpolation through the rest TM), with its statistics over the voxels
// whose centre lies in the TM. Other voxels hold -1.
struct GridError {
  ScalarGrid field;
  double mean = 0.0;             // e_mean over the covered voxels
  double max = 0.0;
  std::int64_t coveredVoxels = 0;
};
GridError gridDeformationError(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed, const GridGeometry& geometry,
                               const VertexFieldInterpolation& interpolate);

// An edge of a TM: two vertex indices.
using TetEdge = std::array<std::int32_t, 2>;

// Edge bisections of a TM, one at a time, with the tets of every vertex
// kept up to date so that a split costs the tets around its edge. The mesh
// must outlive the bisection and change only through it.
class EdgeBisection {
public:
  explicit EdgeBisection(TetMesh& mesh);
  // The tets holding edge (a, b), ascending (empty when it is no edge of the
  // mesh). Valid until the next call.
  const std::vector<std::int32_t>& tetsAround(TetEdge edge);
  // Splits the edge at its midpoint, the new vertex #V: each tet holding it
  // (tetsAround order) becomes the tet with b replaced by the midpoint (in
  // its place) and the tet with a replaced by it (appended, in the same
  // order), both with its label. Returns how many tets it appended.
  // RuntimeFailure for a pair of vertices that is no edge of the mesh.
  std::size_t bisect(TetEdge edge);

private:
  TetMesh& mesh_;
  std::vector<std::vector<std::int32_t>> incident_;  // #V: the tets of each vertex
  std::vector<std::int32_t> around_;
};

// One measured TM of the loop.
struct RefinementStep {
  std::size_t vertices = 0, tets = 0;
  double meanError = 0.0, maxError = 0.0;  // of e_g
  std::size_t splitEdges = 0;              // edges bisected to make the next TM (0: none)
  double seconds = 0.0;                    // splitting and embedding of this TM (0 for the first)
};

struct RefinementResult {
  std::vector<RefinementStep> steps;  // the initial TM, then each refined one
  std::size_t kept = 0;               // the step whose TM the loop ends with: the lowest max e_g
  // "negligible error", "uniform error", "stalled", "iterations", "tet budget", "unsplittable"
  std::string stopReason;
};

// What the loop refines: the initial rest TM, its deformed positions and
// which of its vertices the deformation places itself (1 per vertex; a split
// edge joins two of them); the placement of a round's midpoints (vertices of
// `refined` from deformed.size() on, the midpoints of `parents` in order, a
// parent may be an earlier midpoint), which appends their deformed
// positions to `deformed` and 1 to `placed` for those the deformation
// placed; and the adoption of the TM the loop keeps, with its deformed
// positions and placed flags (not called when it keeps the initial TM).
struct RefinementSubject {
  std::function<const TetMesh&()> restMesh;
  std::function<const std::vector<Eigen::Vector3d>&()> deformedPositions;
  std::function<std::vector<std::uint8_t>()> placedByDeformation;
  std::function<void(const TetMesh& refined, std::span<const TetEdge> parents, std::vector<Eigen::Vector3d>& deformed,
                     std::vector<std::uint8_t>& placed)>
      placeMidpoints;
  std::function<void(TetMesh refined, std::vector<Eigen::Vector3d> deformed, std::vector<std::uint8_t> placed)> adopt;
};

// The loop. The error grid has `geometry` (the working grid's). Progress:
// "refinement".
RefinementResult refineTransferMesh(const RefinementSubject& subject, const GridGeometry& geometry,
                                    const VertexFieldInterpolation& interpolate, const RefinementOptions& options = {});

}  // namespace vox
