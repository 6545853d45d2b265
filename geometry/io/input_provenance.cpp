#include "geometry/io/input_provenance.h"

#include "geometry/io/grid_files.h"
#include "geometry/sha256.h"

#include <filesystem>
#include <system_error>

namespace vox {

Provenance makeProvenance(std::string commandLine, const std::vector<std::pair<std::string, std::string>>& files) {
  Provenance p;
  p.commandLine = std::move(commandLine);
  std::error_code ec;
  p.workingDirectory = std::filesystem::current_path(ec).string();
  auto add = [&](const std::string& role, const std::string& path) {
    const std::uint64_t bytes = std::filesystem::file_size(path, ec);
    p.inputs.push_back({role, path, sha256OfFile(path), ec ? 0 : bytes});
  };
  for (const auto& [role, path] : files) {
    if (path.empty()) continue;
    if (role != "grid") {
      add(role, path);
      continue;
    }
    const std::vector<std::string> parts = gridFiles(path);
    add(role, parts[0]);
    for (std::size_t k = 1; k < parts.size(); ++k) add("grid data", parts[k]);
  }
  return p;
}

}  // namespace vox
