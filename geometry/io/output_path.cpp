#include "geometry/io/output_path.h"

#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <system_error>
#include <unistd.h>

namespace vox {

namespace {

bool endsWith(std::string s, const std::string& suffix) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// The extensions of a kind, or "" when `path` has one of them.
std::string extensionFault(const std::string& path, OutputKind kind) {
  switch (kind) {
    case OutputKind::Grid:
      return hasGridExtension(path) ? "" : "unknown grid format (use .nii, .nii.gz, .mha, .mhd, .nrrd, .nhdr, .inr or .inr.gz)";
    case OutputKind::TetMesh:
      return hasTetMeshExtension(path) ? "" : "unknown tet mesh format (use .mesh, .meshb, .vtu or .msh)";
    case OutputKind::Surface:
      return hasSurfaceExtension(path) ? "" : "unknown surface format (use .obj, .off or .ply)";
    case OutputKind::Png:
      return endsWith(path, ".png") ? "" : "images are written as PNG (use .png)";
    case OutputKind::Json:
      return path == "-" || endsWith(path, ".json") ? "" : "reports are written as JSON (use .json, or - for stdout)";
    case OutputKind::Csv:
      return endsWith(path, ".csv") ? "" : "tables are written as CSV (use .csv)";
    case OutputKind::Text:
      return "";
    case OutputKind::Prepared:
      return endsWith(path, ".vxprep") ? "" : "prepared states are written as .vxprep";
  }
  return "";
}

}  // namespace

void checkOutputPath(const std::string& path, OutputKind kind, const std::string& option) {
  if (path.empty() || (kind == OutputKind::Json && path == "-")) return;
  if (const std::string fault = extensionFault(path, kind); !fault.empty()) throw UsageError(option + " " + path, fault);
  namespace fs = std::filesystem;
  const fs::path target(path);
  std::error_code ec;
  if (fs::is_directory(target, ec)) throw InputError(path, "is a directory");
  const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
  if (!fs::exists(parent, ec)) throw InputError(path, "directory " + parent.string() + " does not exist");
  if (!fs::is_directory(parent, ec)) throw InputError(path, parent.string() + " is not a directory");
  // The writers create a temporary beside the target and rename it: the
  // directory must be writable (the target's own permissions do not matter).
  if (::access(parent.c_str(), W_OK | X_OK) != 0) throw InputError(path, "directory " + parent.string() + " is not writable");
}

}  // namespace vox
