#include "geometry/provenance.h"

#include "geometry/sha256.h"

#include <nlohmann/json.hpp>


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
