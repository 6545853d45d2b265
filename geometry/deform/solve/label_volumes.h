#pragma once
// Label volumes through the deformation, and a posed grid whose per-label
// voxel counts match them.
//
// Nearest-neighbour resampling (rasterize.h) is unbiased but noisy at label
// boundaries: a rigidly rotated thin or small organ gains or loses voxels
// (a 5-voxel label can change by 20 %), which is resampling, not
// deformation. Its volume after the deformation is known exactly from the
// transfer mesh: each source voxel whose centre lies in rest tet t is mapped
// with the Jacobian determinant det J_t = |t'| / |t| of the piecewise-linear
// map, so label l occupies
//   V'_l = sum over its source voxels v in a tet t(v) of det J_t(v) (source voxels)
// after the deformation (the output grid G' has the source spacing, so this
// is a voxel count of G'). Source voxels in no tet are not carried to G' and
// do not count. Label 0 gets the rest of G'.
//
// The correction then relabels boundary voxels of G' until every label's
// count is as near its V'_l as single-voxel moves get it:
//  - every output voxel centre located in a deformed tet is mapped back to
//    its source point p (as the rasterizer does); the trilinear weights of
//    the 8 source voxels around p give each label a fraction w_l there. A
//    voxel whose 8 source voxels all carry its label is not touched;
//  - the candidate moves (voxel: current label a -> label b with w_b > 0)
//    are sorted by w_a - w_b (the most ambiguous voxels first; voxel index
//    and b break ties) and swept in that order; a move is made when it
//    lowers sum_l |count_l - V'_l| / max(V'_l, 1) and the voxel still has
//    label a. Relative deviations let a voxel go from a large label on its
//    target to a small label short of it (one voxel is 0.1 % of a 1000-voxel
//    organ, nothing to a muscle). A voxel changes at most once. Sweeps
//    repeat until one makes no move.
// So only voxels where the source has both labels within one voxel of p
// change, and the result is deterministic (independent of thread count).

#include "geometry/label_grid.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

namespace vox {

// V'_l for every label 0..maxLabel of `source` (index = label), in voxels of
// the source spacing; entry 0 holds the source's label-0 voxels carried by a
// tet. rest: the TM at rest (grid frame, mm); deformed: #V positions.
// Throws InputError for a vertex count mismatch or bad connectivity.
std::vector<double> deformedLabelVolumes(const LabelGrid& source, const TetMesh& rest,
                                         const std::vector<Eigen::Vector3d>& deformed, int threads = 0);

// The source voxels of each rest tet, per label: what V'_l needs besides the
// Jacobians, computed once so that V'_l costs one pass over the tets per
// frame (the viewer's live volume panel). CSR over tets: the voxels of tet t
// are labels / counts [start[t], start[t + 1]).
struct TetLabelVoxels {
  std::vector<std::int64_t> start;  // #T + 1
  std::vector<Label> labels;
  std::vector<std::uint32_t> counts;
  Label maxLabel = 0;
};
TetLabelVoxels tetLabelVoxels(const LabelGrid& source, const TetMesh& rest, int threads = 0);
// V'_l as deformedLabelVolumes computes it, from the voxels of each tet.
std::vector<double> deformedLabelVolumes(const TetLabelVoxels& voxels, const TetMesh& rest,
                                         const std::vector<Eigen::Vector3d>& deformed);

// Gaps the deformation opens inside the body: voxels of `posed` (G' of
// rest -> deformed, as preserveLabelVolumes takes it) that hold background,
// that no deformed tet covers, and that background does not connect to
// G''s border (6-connected). Sliding surfaces that part leave such voids,
// which the source does not have. They are filled from their rim inward,
// each voxel with the most frequent label among its 6 neighbours (ties: the
// lower label), so the tissue closes over them. Labels flagged in `behind`
// (index = label: the bones, which move rigidly and do not flow into a
// gap) fill only what no other label reaches. Voxels a tet covers keep what
// the rasterization gave them (the source's own enclosed background stays).
// Returns the voxels filled. Throws InputError as preserveLabelVolumes.
std::uint64_t fillEnclosedGaps(LabelGrid& posed, const LabelGrid& source, const TetMesh& rest, const std::vector<Eigen::Vector3d>& deformed,
                               int threads = 0, std::span<const std::uint8_t> behind = {});

// A label flagged in `split` (index = label) whose voxels lie in more than
// one region of `regions` (the body parts: a left and a right humerus share
// their labels) gets a key of its own per region, so that the correction
// keeps each region's volume instead of balancing one against the other.
// Keys follow grid.maxLabel() in the order of (label, region); a voxel of
// region 0 keeps its label. `regions` is the grid downsampled by `factor`
// (voxel (i, j, k) takes region (i/f, j/f, k/f)). Nothing is split (labelOf
// empty) when no label spans two regions or the keys would not fit a Label.
struct SplitLabels {
  LabelGrid grid;              // keys where split, the labels elsewhere
  std::vector<Label> labelOf;  // index = key or label: the label it stands for
};
SplitLabels splitLabels(const LabelGrid& grid, std::span<const std::uint8_t> split, const LabelGrid& regions, int factor = 1);

struct LabelVolumeCorrection {
  std::uint64_t candidates = 0;   // voxels whose source neighbourhood holds another label
  std::uint64_t still = 0;        // such voxels left alone: their tet did not move (kStillFraction)
  std::uint64_t relabelled = 0;   // voxels whose label changed
  int sweeps = 0;
  double deviationBefore = 0.0;   // sum over labels of |count_l - V'_l|, voxels
  double deviationAfter = 0.0;
  double worstPercentBefore = 0.0;  // largest |count_l / V'_l - 1| in %, labels > 0 with V'_l >= 0.5
  double worstPercentAfter = 0.0;
  bool toRestVolumes = false;     // targets: the rest volumes (else the deformed ones)
  std::uint64_t gapsFilled = 0;   // voxels of enclosed gaps filled before it (fillEnclosedGaps)
};

// A tet whose vertices all moved by less than this fraction of the finest
// voxel spacing is still: its output voxels are the source's, and the
// correction leaves them alone, so tissue far from the moved parts keeps its
// labels (the Green coordinates move it by a few micrometres).
inline constexpr double kStillFraction = 0.1;

// Relabels boundary voxels of `posed` (G' rasterized from `source` through
// rest -> deformed, samples = 1 or more) so that label l > 0 has about
// targets[l] voxels and label 0 the rest (see above). targets: from
// deformedLabelVolumes (index = label). Throws InputError when posed's
// geometry is not the output grid of this deformation. With fillGapsFirst
// it fills the enclosed gaps first, as fillEnclosedGaps(posed, source, rest,
// deformed, threads, behind) does, from the same located output lattice
// (result.gapsFilled), and corrects the filled grid.
LabelVolumeCorrection preserveLabelVolumes(LabelGrid& posed, const LabelGrid& source, const TetMesh& rest,
                                           const std::vector<Eigen::Vector3d>& deformed, std::span<const double> targets,
                                           int threads = 0, bool fillGapsFirst = false,
                                           std::span<const std::uint8_t> behind = {});

}  // namespace vox
