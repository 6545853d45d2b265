// libFuzzer harness: the PLY surface reader (ascii and binary) on arbitrary bytes.

#include "geometry/io/mesh_io.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  vox::fuzz::readAsFile(data, size, ".ply", [](const std::string& path) { vox::readSurface(path); });
  return 0;
}
