// libFuzzer harness: the pose JSON parser on arbitrary bytes (in memory).

#include "geometry/deform/pose/pose.h"
#include "geometry/error.h"

#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    vox::parsePose(std::string(reinterpret_cast<const char*>(data), size), "pose.json");
  } catch (const vox::InputError&) {
  }
  return 0;
}
