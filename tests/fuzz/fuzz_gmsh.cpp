// libFuzzer harness: the Gmsh MSH 4.1 reader (ASCII and binary) on arbitrary bytes.

#include "geometry/io/mesh_io.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  vox::fuzz::readAsFile(data, size, ".msh", [](const std::string& path) { vox::readTetMesh(path); });
  return 0;
}
