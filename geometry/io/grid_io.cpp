#include "geometry/io/grid_io.h"

#include "geometry/ascii_text.h"
#include "geometry/error.h"


namespace vox {

bool hasGridExtension(const std::string& path) {
  for (const char* e : {".nii", ".nii.gz", ".mha", ".mhd", ".nrrd", ".nhdr", ".inr", ".inr.gz"})
    if (endsWithIgnoringCase(path, e)) return true;
  return false;
}

GridFormat gridFormatFromPath(const std::string& path) {
  const auto endsWith = [&](const char* suffix) { return endsWithIgnoringCase(path, suffix); };
  if (endsWith(".nii") || endsWith(".nii.gz")) return GridFormat::Nifti;
  if (endsWith(".mha") || endsWith(".mhd")) return GridFormat::MetaImage;
  if (endsWith(".nrrd") || endsWith(".nhdr")) return GridFormat::Nrrd;
  if (endsWith(".inr") || endsWith(".inr.gz")) return GridFormat::Inr;
  throw InputError(path, "unknown grid format (expected .nii, .nii.gz, .mha, .mhd, .nrrd, .nhdr, .inr or .inr.gz)");
}

LabelGrid readGrid(const std::string& path) {
  switch (gridFormatFromPath(path)) {
    case GridFormat::Nifti: return readNifti(path);
    case GridFormat::MetaImage: return readMetaImage(path);
    case GridFormat::Nrrd: return readNrrd(path);
    case GridFormat::Inr: return readInr(path);
  }
  throw InputError(path, "unknown grid format");
}

void writeGrid(const std::string& path, const LabelGrid& grid) {
  switch (gridFormatFromPath(path)) {
    case GridFormat::Nifti: return writeNifti(path, grid);
    case GridFormat::MetaImage: return writeMetaImage(path, grid);
    case GridFormat::Nrrd: return writeNrrd(path, grid);
    case GridFormat::Inr: return writeInr(path, grid);
  }
}

}  // namespace vox
