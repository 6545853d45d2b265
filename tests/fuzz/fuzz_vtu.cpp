// libFuzzer harness: the VTK XML unstructured grid (.vtu) reader (ascii, base64, raw appended, zlib) on arbitrary bytes.

#include "geometry/io/mesh_io.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  vox::fuzz::readAsFile(data, size, ".vtu", [](const std::string& path) { vox::readTetMesh(path); });
  return 0;
}
