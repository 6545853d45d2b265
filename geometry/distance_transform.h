#pragma once
// Exact Euclidean distance transform on anisotropic grids (distances in mm,
// not voxel steps), and the grid padding the morphological steps of the
// cage and transfer-mesh builders need to grow past the input's borders.

#include "geometry/label_grid.h"
#include "geometry/scalar_grid.h"

#include <cstdint>
#include <vector>

namespace vox {

// `geometry` grown by pad[a] voxels on both sides of axis a; voxel (i,j,k) of
// the result sits where voxel (i - pad0, j - pad1, k - pad2) of the input
// sits, so grid-frame positions are unchanged.
GridGeometry padGeometry(const GridGeometry& geometry, const Index3& pad);

// Voxels to pad on each side so that a band `distanceMm` wide around the
// grid's content fits, plus `margin` voxels.
Index3 padForDistance(const GridGeometry& geometry, double distanceMm, std::int64_t margin);

// Copies `grid` into the padded geometry `padded` (from padGeometry), 0 outside.
LabelGrid padLabels(const LabelGrid& grid, const GridGeometry& padded);

struct DistanceTransform {
  ScalarGrid distance;                // mm from each voxel centre to the nearest seed centre; +inf without seeds
  std::vector<std::int64_t> nearest;  // #voxels linear index of that seed (-1 without seeds); empty unless requested
};

// Distance from every voxel centre to the nearest voxel centre where
// `seeds` is non-zero (Felzenszwalb-Huttenlocher lower envelopes of
// parabolas, one pass per axis with that axis' spacing). `seeds` has
// geometry.voxelCount() entries, x fastest. With `withNearest`, also the
// feature transform (index of the nearest seed; ties go to the seed found
// first along each pass, deterministically).
DistanceTransform euclideanDistanceTransform(const GridGeometry& geometry, const std::vector<std::uint8_t>& seeds,
                                             bool withNearest = false);

}  // namespace vox
