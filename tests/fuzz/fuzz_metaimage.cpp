// libFuzzer harness: the MetaImage reader (.mha; raw or CompressedData = True) on arbitrary bytes.

#include "geometry/io/grid_io.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  vox::fuzz::readAsFile(data, size, ".mha", [](const std::string& path) { vox::readGrid(path); });
  return 0;
}
