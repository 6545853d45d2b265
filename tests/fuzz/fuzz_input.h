#pragma once
// What every reader harness shares: the readers take paths, so the input is
// written to a file of this process (under $TMPDIR, named with the format's
// extension), read back and removed. A reader may reject the bytes with InputError;
// any other exception, crash, sanitizer report, leak or allocation beyond
// libFuzzer's limit (-rss_limit_mb) is a finding.

#include "geometry/error.h"

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace vox::fuzz {

inline std::string inputPath(const char* extension) {
  const char* dir = std::getenv("TMPDIR");
  return std::string(dir && *dir ? dir : "/tmp") + "/voxmorph_fuzz_" + std::to_string(::getpid()) + extension;
}

template <class Read>
void readAsFile(const std::uint8_t* data, std::size_t size, const char* extension, Read read) {
  static const std::string path = inputPath(extension);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  try {
    read(path);
  } catch (const InputError&) {
  }
  // Removed before its pages are written back: rewriting one file in place
  // would make the file system flush it on every input.
  std::remove(path.c_str());
}

}  // namespace vox::fuzz
