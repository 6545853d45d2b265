#pragma once
// What a report records so that its result can be reproduced: the voxmorph
// build (project version and `git describe --always --dirty` of the source
// at build time), the command line and working directory, and the SHA-256
// of every input file (grid, organ table, pose, mesh, cage). Every report
// voxmorph writes carries it as "provenance".

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace vox {

// The project version ("0.1.0").
std::string voxmorphVersion();
// `git describe --always --dirty` of the source tree when it was built
// ("9ef006c-dirty"), "" when it was not built from a git checkout.
std::string voxmorphGitDescribe();
// "voxmorph 0.1.0 (git 9ef006c-dirty)", or "voxmorph 0.1.0" without git.
std::string voxmorphVersionLine();

struct InputDigest {
  std::string role;    // "grid", "grid data", "organs", "pose", "mesh", "cage"
  std::string path;    // as given (a file), or a description of text inputs
  std::string sha256;  // of the file's bytes (or the text's), 64 hex digits
  std::uint64_t bytes = 0;
};

struct Provenance {
  std::string version = voxmorphVersion();
  std::string gitDescribe = voxmorphGitDescribe();
  std::string commandLine;       // shell-quoted: pasting it re-runs the command
  std::string workingDirectory;  // where relative paths of the command line start
  std::vector<InputDigest> inputs;
};

// Quotes one argument for a POSIX shell where it needs it ('a b' -> 'a b'
// in single quotes, plain words unchanged).
std::string shellQuoted(std::string_view argument);
std::string shellCommandLine(int argc, const char* const* argv);

// Records an input that is not a file (a pose edited in the viewer) by the
// digest of its text.
void addTextInput(Provenance& provenance, const std::string& role, const std::string& description, std::string_view text);

// The "provenance" object of a report, as JSON text:
// {"voxmorph_version", "git_describe" (null without git), "command_line",
//  "working_directory", "inputs": [{"role", "path", "sha256", "bytes"}]}.
std::string provenanceJson(const Provenance& provenance);

}  // namespace vox
