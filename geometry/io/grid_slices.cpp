// Streaming access by whole z-slices: each format's reader and writer are
// slice-based already (grid_stream.h); this picks one by extension.

#include "geometry/ascii_text.h"
#include "geometry/io/grid_stream.h"

namespace vox {

std::unique_ptr<GridSliceReader> openGridSlices(const std::string& path) {
  switch (gridFormatFromPath(path)) {
    case GridFormat::Nifti: return openNiftiSlices(path);
    case GridFormat::MetaImage: return openMetaImageSlices(path);
    case GridFormat::Nrrd: return openNrrdSlices(path);
    case GridFormat::Inr: return openInrSlices(path);
  }
  return openNiftiSlices(path);
}

bool gridSlicesSeekable(const std::string& path) { return endsWithIgnoringCase(path, ".nii"); }

std::unique_ptr<GridSliceWriter> createGridSlices(const std::string& path, const GridGeometry& geometry, Label maxLabel) {
  switch (gridFormatFromPath(path)) {
    case GridFormat::Nifti: return createNiftiSlices(path, geometry, maxLabel);
    case GridFormat::MetaImage: return createMetaImageSlices(path, geometry, maxLabel);
    case GridFormat::Nrrd: return createNrrdSlices(path, geometry, maxLabel);
    case GridFormat::Inr: return createInrSlices(path, geometry, maxLabel);
  }
  return createNiftiSlices(path, geometry, maxLabel);
}

}  // namespace vox
