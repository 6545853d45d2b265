// libFuzzer harness: the viewer's session script reader (`voxmorph view
// --script`) on arbitrary bytes.

#include "app/viewer/viewer_script.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  vox::fuzz::readAsFile(data, size, ".json", [](const std::string& path) { vox::app::readViewerScript(path); });
  return 0;
}
