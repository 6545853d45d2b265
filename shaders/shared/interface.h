// Structs and binding numbers shared by the C++ host code (gpu/) and the GLSL
// kernels (shaders/*.comp). Plain 32-bit scalars only, so std430 and C++
// layouts agree; the C++ side checks sizes with static_assert.
#ifndef VOXMORPH_SHADER_INTERFACE_H
#define VOXMORPH_SHADER_INTERFACE_H

#ifdef __cplusplus
#include <cstdint>
namespace vox::shader {
using uint = std::uint32_t;
#endif

// ---------------------------------------------------------------- label_stats
// Per-label voxel counts and bounding boxes of a chunk of a label grid.
#define VOX_LABEL_STATS_BINDING_LABELS 0  // uint[]: two uint16 labels per word
#define VOX_LABEL_STATS_BINDING_COUNTS 1  // uint[labelCount]
#define VOX_LABEL_STATS_BINDING_BOXES 2   // uint[6 * labelCount]: min xyz, max xyz
#define VOX_LABEL_STATS_GROUP_SIZE 64
#define VOX_LABEL_STATS_VOXELS_PER_THREAD 64

struct LabelStatsPush {
  uint voxelCount;  // voxels in this chunk
  uint labelCount;  // labels >= labelCount are ignored
  uint nx;
  uint ny;
  uint startX;      // grid coordinates of the chunk's first voxel
  uint startY;
  uint startZ;
  uint pad;
};

#ifdef __cplusplus
static_assert(sizeof(LabelStatsPush) == 32);
}  // namespace vox::shader
#endif

#endif
