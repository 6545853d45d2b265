#version 460
// Reduce stage (CPU reference: reduceSamples in geometry/deform/rasterize.cpp):
// one invocation per pair of output voxels of the slab. Each of the k^3
// samples of a voxel is resolved through the last source window, the voxel
// takes the most frequent label (ties to the lowest), and the pair is packed
// into one word.
#extension GL_GOOGLE_include_directive : require
#include "shared/interface.h"

layout(local_size_x = VOX_RASTER_GROUP_SIZE) in;

layout(std430, binding = VOX_RASTER_BINDING_STATE) readonly buffer State { uint state[]; };
layout(std430, binding = VOX_RASTER_BINDING_OUTPUT) writeonly buffer Output { uint packedOutput[]; };
layout(push_constant) uniform Push { RasterResolvePush pc; };

#include "shared/rasterize_source.glsl"

uint voxelLabel(uint v) {
  if (v >= pc.voxelCount) return 0u;
  const uint i = v % pc.outputNx;
  const uint r = v / pc.outputNx;
  const uint j = r % pc.outputNy;
  const uint l = r / pc.outputNy;
  const uint k = pc.samples;
  if (k == 1u) return sampleLabel(resolveSample(state[v], ivec3(i, j, pc.slabZ0 + l)));

  uint labels[VOX_RASTER_MAX_SAMPLES * VOX_RASTER_MAX_SAMPLES * VOX_RASTER_MAX_SAMPLES];
  uint n = 0u;
  bool uniformLabel = true;
  for (uint c = 0u; c < k; ++c)
    for (uint b = 0u; b < k; ++b)
      for (uint a = 0u; a < k; ++a) {
        const uvec3 q = uvec3(i * k + a, j * k + b, l * k + c);
        const uint s = (q.z * pc.latticeNy + q.y) * pc.latticeNx + q.x;
        labels[n] = sampleLabel(resolveSample(state[s], ivec3(q.x, q.y, pc.slabZ0 + q.z)));
        uniformLabel = uniformLabel && labels[n] == labels[0];
        ++n;
      }
  if (uniformLabel) return labels[0];
  uint best = 0u;
  uint bestCount = 0u;
  for (uint x = 0u; x < n; ++x) {
    uint count = 0u;
    for (uint y = 0u; y < n; ++y) count += labels[y] == labels[x] ? 1u : 0u;
    if (count > bestCount || (count == bestCount && labels[x] < best)) {
      best = labels[x];
      bestCount = count;
    }
  }
  return best;
}

void main() {
  if (gl_GlobalInvocationID.x >= pc.itemCount) return;
  const uint p = pc.itemBase + gl_GlobalInvocationID.x;
  packedOutput[p] = voxelLabel(2u * p) | (voxelLabel(2u * p + 1u) << 16);
}
