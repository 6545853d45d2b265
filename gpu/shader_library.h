#pragma once
// SPIR-V compiled from shaders/*.comp at build time and embedded in the
// binary (see shaders/CMakeLists.txt). Names are file names: "label_stats.comp".

#include <cstdint>
#include <span>
#include <string_view>

namespace vox::gpu {

// Throws RuntimeFailure when no shader has that name.
std::span<const std::uint32_t> embeddedShader(std::string_view name);

}  // namespace vox::gpu
