// libFuzzer harness: the NRRD reader (raw or gzip encoding) on arbitrary bytes.

#include "geometry/io/grid_io.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  vox::fuzz::readAsFile(data, size, ".nrrd", [](const std::string& path) { vox::readGrid(path); });
  return 0;
}
