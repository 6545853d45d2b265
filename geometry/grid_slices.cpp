#include "geometry/grid_slices.h"

#include <algorithm>

namespace vox {

void LabelGridSlices::readSlices(std::int64_t k0, std::int64_t count, Label* out) {
  const std::int64_t slice = grid_.geometry().sliceVoxels();
  std::copy(grid_.data() + k0 * slice, grid_.data() + (k0 + count) * slice, out);
}

}  // namespace vox
