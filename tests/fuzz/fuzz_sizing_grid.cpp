// libFuzzer harness: the remesher's sizing grid reader (a NIfTI-1 of mm values; plain, and gzip when the bytes start with its
// magic) on arbitrary bytes.

#include "geometry/io/sizing_grid_io.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  vox::fuzz::readAsFile(data, size, ".nii", [](const std::string& path) { vox::readSizingGrid(path); });
  return 0;
}
