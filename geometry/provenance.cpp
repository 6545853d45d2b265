#include "geometry/provenance.h"

#include "geometry/io/grid_files.h"
#include "geometry/sha256.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <system_error>

namespace vox {

std::string voxmorphVersionLine() {
  const std::string git = voxmorphGitDescribe();
  return "voxmorph " + voxmorphVersion() + (git.empty() ? "" : " (git " + git + ")");
}

std::string shellQuoted(std::string_view a) {
  const bool plain = !a.empty() && a.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-+=./:,@%") ==
                                       std::string_view::npos;
  if (plain) return std::string(a);
  std::string q = "'";
  for (const char c : a) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string shellCommandLine(int argc, const char* const* argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) line += (i ? " " : "") + shellQuoted(argv[i]);
  return line;
}

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

void addTextInput(Provenance& p, const std::string& role, const std::string& description, std::string_view text) {
  p.inputs.push_back({role, description, sha256Hex(text), text.size()});
}

std::string provenanceJson(const Provenance& p) {
  nlohmann::json inputs = nlohmann::json::array();
  for (const InputDigest& d : p.inputs) inputs.push_back({{"role", d.role}, {"path", d.path}, {"sha256", d.sha256}, {"bytes", d.bytes}});
  nlohmann::json j = {{"voxmorph_version", p.version},
                      {"git_describe", p.gitDescribe.empty() ? nlohmann::json(nullptr) : nlohmann::json(p.gitDescribe)},
                      {"command_line", p.commandLine},
                      {"working_directory", p.workingDirectory},
                      {"inputs", inputs}};
  return j.dump();
}

}  // namespace vox
