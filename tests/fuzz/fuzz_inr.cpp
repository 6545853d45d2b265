// libFuzzer harness: the INR reader (plain, and .inr.gz when the bytes start with the gzip magic) on arbitrary bytes.

#include "geometry/io/grid_io.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  vox::fuzz::readAsFile(data, size, ".inr", [](const std::string& path) { vox::readGrid(path); });
  return 0;
}
