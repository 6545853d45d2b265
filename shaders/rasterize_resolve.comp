#version 460
// Resolve stage for every source window but the last (the reduce stage
// resolves the last one itself): one invocation per sample of the slab.
#extension GL_GOOGLE_include_directive : require
#include "shared/interface.h"

layout(local_size_x = VOX_RASTER_GROUP_SIZE) in;

layout(std430, binding = VOX_RASTER_BINDING_STATE) buffer State { uint state[]; };
layout(push_constant) uniform Push { RasterResolvePush pc; };

#include "shared/rasterize_source.glsl"

void main() {
  if (gl_GlobalInvocationID.x >= pc.itemCount) return;
  const uint s = pc.itemBase + gl_GlobalInvocationID.x;
  const uint st = state[s];
  if ((st & VOX_RASTER_RESOLVED) != 0u) return;
  const uint row = s / pc.latticeNx;
  const ivec3 q = ivec3(s % pc.latticeNx, row % pc.latticeNy, pc.slabZ0 + row / pc.latticeNy);
  const uint next = resolveSample(st, q);
  if (next != st) state[s] = next;
}
