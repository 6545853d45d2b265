#pragma once
// Deformation-adaptive refinement of the transfer mesh (thesis 4.2.2,
// eq. 4.5-4.7). The TM linearizes the deformation tet by tet; where the
// basis change B_t varies between neighbouring tets the linearization errs,
// so the TM is regenerated there with smaller tets:
//   e_t = ||Delta B_t||                                     (eq. 4.5)
//   e_v = volume-weighted mean of e_t around v              (eq. 4.6)
//   e_g = e_v interpolated onto the grid through the rest TM
//   F[g] <- F[g] cbrt(e_mean / max(e_g[g], e_mean))          (eq. 4.7)
// then the TM is rebuilt under F, deformed by the same pose, and measured
// again.
//
// Eq. 4.7 scales the tet volume near g by e_mean / max(e_g, e_mean), so the
// tet density grows by max(e_g, e_mean) / e_mean, whose mean over the grid is
// at most 2: one iteration at most doubles the TM. The tet count of the next
// TM is predicted from the density ratio (sum of (F_old / F_new)^3); when it
// would exceed the budget, the update is applied partially
// (F_old * factor^s with s < 1, the largest s that fits). The prediction is
// rough: the mesher's tet count does not follow F^-3 closely (adult male arm
// pose: a second regeneration went from 124k to 451k tets against a 250k
// budget), so one regeneration is the default.
//
// Stopping (the error is "uniform" or the budget is spent), checked before
// each regeneration:
//  - negligible: max e_g <= negligibleError (a rigid or identity pose);
//  - uniform: max e_g <= uniformRatio * e_mean;
//  - stalled: max e_g fell by less than minImprovement since the last TM;
//  - budget: maxIterations regenerations done, or the partial update that
//    fits maxTets would change F by less than a few percent.

#include "geometry/label_grid.h"
#include "geometry/raster/field_interpolation.h"
#include "geometry/scalar_grid.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace vox {

struct RefinementOptions {
  int maxIterations = 1;            // TM regenerations at most (0: measure the error only)
  std::int64_t maxTets = 250000;    // tet budget of a regenerated TM
  double uniformRatio = 4.0;        // uniform when max e_g <= uniformRatio * e_mean
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

// Eq. 4.7 raised to `strength` s in [0, 1]: F[g] *= cbrt(e_mean / max(e_g,
// e_mean))^s on the covered voxels; the voxels just off the TM take the
// factor of their covered neighbours (the mesher samples F there too).
// Returns the predicted tet count ratio of the TM under the new F: the mean
// of (F_old / F_new)^3 over the covered voxels.
double updateSizingField(ScalarGrid& sizing, const GridError& error, double strength = 1.0);

// One measured TM of the loop.
struct RefinementStep {
  std::size_t vertices = 0, tets = 0;
  double meanError = 0.0, maxError = 0.0;  // of e_g
  double strength = 0.0;                   // s of the update that produced the next TM (0: none)
  double seconds = 0.0;                    // regeneration and deformation of this TM (0 for the first)
};

struct RefinementResult {
  std::vector<RefinementStep> steps;  // the initial TM, then each regenerated one
  std::string stopReason;             // "negligible error", "uniform error", "stalled", "iterations", "tet budget"
};

// What the loop refines: the current rest TM and its deformed positions, and
// the regeneration of the TM under a new sizing field, deformed by the same
// pose (after which restMesh / deformedPositions return the new TM).
struct RefinementSubject {
  std::function<const TetMesh&()> restMesh;
  std::function<const std::vector<Eigen::Vector3d>&()> deformedPositions;
  std::function<void(const ScalarGrid& sizing)> regenerate;
};

// The loop. `sizing` (F, updated in place) and the error grid share one
// geometry (the working grid's). Progress: "refinement".
RefinementResult refineTransferMesh(const RefinementSubject& subject, ScalarGrid& sizing,
                                    const VertexFieldInterpolation& interpolate, const RefinementOptions& options = {});

}  // namespace vox
