// Formats not implemented yet: each entry throws. Entries are removed as the
// readers and writers land; this file must be empty of entries (and deleted)
// before a release.
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/mesh_io.h"

namespace vox {

namespace {
[[noreturn]] void pending(const std::string& path) { throw RuntimeFailure(path + ": format not supported yet"); }
}  // namespace

// grid formats
LabelGrid readNifti(const std::string& path) { pending(path); }
void writeNifti(const std::string& path, const LabelGrid&) { pending(path); }
LabelGrid readMetaImage(const std::string& path) { pending(path); }
void writeMetaImage(const std::string& path, const LabelGrid&) { pending(path); }
LabelGrid readNrrd(const std::string& path) { pending(path); }
void writeNrrd(const std::string& path, const LabelGrid&) { pending(path); }
LabelGrid readInr(const std::string& path) { pending(path); }
void writeInr(const std::string& path, const LabelGrid&) { pending(path); }
std::unique_ptr<GridSliceReader> openGridSlices(const std::string& path) { pending(path); }
std::unique_ptr<GridSliceWriter> createGridSlices(const std::string& path, const GridGeometry&, Label) { pending(path); }

}  // namespace vox
