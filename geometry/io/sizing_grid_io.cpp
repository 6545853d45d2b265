#include "geometry/io/sizing_grid_io.h"

// As in nifti_io.cpp: niftilib is built with zlib.
#ifndef HAVE_ZLIB
#define HAVE_ZLIB 1
#endif
#include <nifti1_io.h>

#include "geometry/error.h"
#include "geometry/io/grid_stream.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <system_error>

namespace vox {

namespace {

struct NiftiImageFree {
  void operator()(nifti_image* image) const { nifti_image_free(image); }
};

template <typename T>
void convert(const void* data, std::size_t count, double slope, double intercept, std::vector<float>& out) {
  const T* in = static_cast<const T*>(data);
  for (std::size_t i = 0; i < count; ++i) out[i] = float(slope * double(in[i]) + intercept);
}

}  // namespace

ScalarGrid readSizingGrid(const std::string& path) {
  std::error_code error;
  const auto fileBytes = std::filesystem::file_size(path, error);
  if (error) throw InputError(path, "cannot open the file (" + error.message() + ")");
  nifti_set_debug_level(0);
  std::unique_ptr<nifti_image, NiftiImageFree> image(nifti_image_read(path.c_str(), 0));
  if (!image) throw InputError(path, "not a readable NIfTI-1 file");
  if (image->nifti_type != NIFTI_FTYPE_NIFTI1_1) throw InputError(path, "only single-file NIfTI-1 grids (.nii, .nii.gz) are supported");
  if (image->ndim < 3 || image->nt > 1 || image->nu > 1 || image->nv > 1 || image->nw > 1)
    throw InputError(path, "only 3-D grids are supported (extra dimensions must be 1)");
  const Index3 dims{image->nx, image->ny, image->nz};
  checkGridDims(path, dims);
  // Before the samples are allocated: the file must be able to hold them
  // (deflate's largest ratio is 1032:1 for a .gz).
  const double bytes = double(dims[0]) * double(dims[1]) * double(dims[2]) * double(image->nbyper);
  const bool gzip = path.size() > 3 && path.compare(path.size() - 3, 3, ".gz") == 0;
  if (bytes > double(fileBytes) * (gzip ? 1032.0 : 1.0))
    throw InputError(path, "the file is too short for its " + std::to_string(dims[0] * dims[1] * dims[2]) + " voxels");

  Eigen::Matrix3d linear;
  Eigen::Vector3d translation;
  const mat44& m = image->sform_code > 0 ? image->sto_xyz : image->qto_xyz;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) linear(r, c) = m.m[r][c];
    translation[r] = m.m[r][3];
  }
  if (!linear.allFinite() || !translation.allFinite()) throw InputError(path, "the affine (sform or qform) is not finite");
  ScalarGrid grid;
  grid.geometry = geometryFromAffine(path, dims, linear, translation);

  switch (image->datatype) {
    case DT_UINT8: case DT_INT8: case DT_UINT16: case DT_INT16: case DT_UINT32: case DT_INT32: case DT_FLOAT32:
    case DT_FLOAT64: break;
    default:
      throw InputError(path, std::string("datatype ") + nifti_datatype_string(image->datatype) +
                                 " is not supported for sizes (expected an integer or float type)");
  }
  if (nifti_image_load(image.get()) != 0 || !image->data) throw InputError(path, "the voxel data is truncated or unreadable");
  const bool scaled = std::isfinite(image->scl_slope) && image->scl_slope != 0.0f;
  const double slope = scaled ? image->scl_slope : 1.0, intercept = scaled ? image->scl_inter : 0.0;
  const std::size_t count = std::size_t(grid.geometry.voxelCount());
  grid.values.resize(count);
  switch (image->datatype) {
    case DT_UINT8: convert<std::uint8_t>(image->data, count, slope, intercept, grid.values); break;
    case DT_INT8: convert<std::int8_t>(image->data, count, slope, intercept, grid.values); break;
    case DT_UINT16: convert<std::uint16_t>(image->data, count, slope, intercept, grid.values); break;
    case DT_INT16: convert<std::int16_t>(image->data, count, slope, intercept, grid.values); break;
    case DT_UINT32: convert<std::uint32_t>(image->data, count, slope, intercept, grid.values); break;
    case DT_INT32: convert<std::int32_t>(image->data, count, slope, intercept, grid.values); break;
    case DT_FLOAT32: convert<float>(image->data, count, slope, intercept, grid.values); break;
    default: convert<double>(image->data, count, slope, intercept, grid.values); break;
  }
  return grid;
}

}  // namespace vox
