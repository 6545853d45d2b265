#pragma once
// Paths and process helpers for the test suites.

#include <filesystem>
#include <string>
#include <vector>

namespace vox::test {

// assets/<name> in the source tree.
std::string assetPath(const std::string& name);
// A fresh empty directory for the current test (under the build tree).
std::string tempDir();
// The built `voxmorph` executable.
std::string voxmorphBinary();
// GTEST_SKIP()s the calling test when the executable was not built (the asan
// preset builds the io tests alone).
#define VOX_REQUIRE_VOXMORPH()                                                              \
  do {                                                                                      \
    if (!std::filesystem::exists(::vox::test::voxmorphBinary())) GTEST_SKIP() << "voxmorph not built"; \
  } while (0)
// Debian's python3 (with nibabel and meshio), or "" when missing.
std::string python();

struct CommandResult {
  int exitCode = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};
// Runs `command` through /bin/sh and captures its output.
CommandResult runCommand(const std::string& command);
// Shell-quotes one argument.
std::string quote(const std::string& s);

// Every regular file in `dir` (names only), sorted.
std::string listFiles(const std::string& dir);
// The lines, each ended by '\n' ("" for none): readable failure messages of lists.
std::string joinLines(const std::vector<std::string>& lines);

// A file's bytes ("" when it cannot be read), and writing bytes to a file.
std::string readText(const std::string& path);
void writeText(const std::string& path, const std::string& text);

}  // namespace vox::test
