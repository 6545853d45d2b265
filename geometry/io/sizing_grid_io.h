#pragma once
// Grids of real values in mm (the remesher's `--size-grid`): a NIfTI-1 file
// (.nii, .nii.gz) of any integer or float type, scaled by scl_slope /
// scl_inter, in its own affine (sform, else qform, else pixdim).

#include "geometry/scalar_grid.h"

#include <string>

namespace vox {

// Throws InputError(path, ...) for a file that is not a readable 3-D NIfTI-1
// grid (the label grid reader's header check, nifti_header.h, with its
// messages), or whose voxel bytes the file cannot hold. Values beyond
// float's range come back infinite, for the caller's checks.
ScalarGrid readSizingGrid(const std::string& path);

}  // namespace vox
