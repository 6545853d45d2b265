#include "geometry/io/grid_files.h"

#include "geometry/io/grid_io.h"
#include "geometry/io/grid_stream.h"

namespace vox {

std::vector<std::string> gridFiles(const std::string& path) {
  std::string data;
  switch (gridFormatFromPath(path)) {
    case GridFormat::MetaImage: data = metaImageDataFile(path); break;
    case GridFormat::Nrrd: data = nrrdDataFile(path); break;
    case GridFormat::Nifti:
    case GridFormat::Inr: break;
  }
  std::vector<std::string> files{path};
  if (!data.empty()) files.push_back(data);
  return files;
}

}  // namespace vox
