#version 460
// Reduce stage (CPU reference: reduceSamples in geometry/raster/rasterize.cpp):
// one invocation per run of VOX_RASTER_REDUCE_RUN consecutive output voxels
// of the slab. A voxel takes the most frequent label of its k^3 resolved
// samples (ties to the lowest; no tet or still pending: 0), and pairs of
// labels are packed into words.
#extension GL_GOOGLE_include_directive : require
#include "shared/interface.h"

layout(local_size_x = VOX_RASTER_REDUCE_GROUP_SIZE) in;
layout(constant_id = 0) const uint kSamples = 1;  // k
const uint kSampleCount = kSamples * kSamples * kSamples;

layout(std430, binding = VOX_RASTER_BINDING_STATE) readonly buffer State { uint state[]; };
layout(std430, binding = VOX_RASTER_REDUCE_BINDING_OUTPUT) writeonly buffer Output { uint packedOutput[]; };
layout(push_constant) uniform Push { RasterReducePush pc; };

uint sampleLabel(uint st) { return (st & VOX_RASTER_RESOLVED) != 0u && st != VOX_RASTER_NO_TET ? (st & 0xFFFFu) : 0u; }

uint voxelLabel(uint v, uint i, uint j, uint l) {
  if (kSamples == 1u) return sampleLabel(state[v]);
  uint labels[kSampleCount];
  bool uniformLabel = true;
  uint n = 0u;
  for (uint c = 0u; c < kSamples; ++c)
    for (uint b = 0u; b < kSamples; ++b)
      for (uint a = 0u; a < kSamples; ++a) {
        labels[n] = sampleLabel(state[((l * kSamples + c) * pc.latticeNy + j * kSamples + b) * pc.latticeNx + i * kSamples + a]);
        uniformLabel = uniformLabel && labels[n] == labels[0];
        ++n;
      }
  if (uniformLabel) return labels[0];
  uint best = 0u;
  uint bestCount = 0u;
  for (uint x = 0u; x < kSampleCount; ++x) {
    uint count = 0u;
    for (uint y = 0u; y < kSampleCount; ++y) count += labels[y] == labels[x] ? 1u : 0u;
    if (count > bestCount || (count == bestCount && labels[x] < best)) {
      best = labels[x];
      bestCount = count;
    }
  }
  return best;
}

void main() {
  if (gl_GlobalInvocationID.x >= pc.runCount) return;
  uint v = (pc.runBase + gl_GlobalInvocationID.x) * VOX_RASTER_REDUCE_RUN;
  uint i = v % pc.outputNx;
  const uint r = v / pc.outputNx;
  uint j = r % pc.outputNy;
  uint l = r / pc.outputNy;
  uint low = 0u;
  for (uint n = 0u; n < VOX_RASTER_REDUCE_RUN; ++n, ++v) {
    const uint label = v < pc.voxelCount ? voxelLabel(v, i, j, l) : 0u;
    if ((n & 1u) == 0u) low = label;
    else packedOutput[v >> 1] = low | (label << 16);
    if (++i == pc.outputNx) {
      i = 0u;
      if (++j == pc.outputNy) {
        j = 0u;
        ++l;
      }
    }
  }
}
