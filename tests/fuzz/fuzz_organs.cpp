// libFuzzer harness: the organ table reader on arbitrary bytes.

#include "geometry/organ_table.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  vox::fuzz::readAsFile(data, size, ".dat", [](const std::string& path) { vox::OrganTable::read(path); });
  return 0;
}
