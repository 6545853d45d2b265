#include "geometry/io/grid_io.h"

#include "geometry/error.h"

#include <algorithm>
#include <cctype>

namespace vox {

namespace {
std::string lowerName(const std::string& path) {
  std::string s = path;
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}
bool endsWith(const std::string& s, const char* suffix) {
  const std::string x(suffix);
  return s.size() >= x.size() && s.compare(s.size() - x.size(), x.size(), x) == 0;
}
}  // namespace

bool hasGridExtension(const std::string& path) {
  const std::string s = lowerName(path);
  for (const char* e : {".nii", ".nii.gz", ".mha", ".mhd", ".nrrd", ".nhdr", ".inr", ".inr.gz"})
    if (endsWith(s, e)) return true;
  return false;
}

GridFormat gridFormatFromPath(const std::string& path) {
  const std::string s = lowerName(path);
  if (endsWith(s, ".nii") || endsWith(s, ".nii.gz")) return GridFormat::Nifti;
  if (endsWith(s, ".mha") || endsWith(s, ".mhd")) return GridFormat::MetaImage;
  if (endsWith(s, ".nrrd") || endsWith(s, ".nhdr")) return GridFormat::Nrrd;
  if (endsWith(s, ".inr") || endsWith(s, ".inr.gz")) return GridFormat::Inr;
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
