#version 460
// Locate stage (CPU reference: locateLatticePoints in
// geometry/deform/lattice_tets.cpp): each task scans a few rows of one tet on
// one lattice slice and claims the points of its spans with atomicMin of the
// slab-local tet index. Local indices ascend with the TM index, so every
// sample ends with the lowest-index tet whose closed test it passes,
// whatever the execution order.
#extension GL_GOOGLE_include_directive : require
#include "shared/interface.h"
#include "shared/lattice_span.glsl"

layout(local_size_x = VOX_RASTER_LOCATE_GROUP_SIZE) in;

layout(std430, binding = VOX_RASTER_LOCATE_BINDING_TETS) readonly buffer Tets { RasterTet tets[]; };
layout(std430, binding = VOX_RASTER_LOCATE_BINDING_TASKS) readonly buffer Tasks { uint tasks[]; };
layout(std430, binding = VOX_RASTER_BINDING_STATE) buffer State { uint state[]; };
layout(push_constant) uniform Push { RasterLocatePush pc; };

void main() {
  if (gl_GlobalInvocationID.x >= pc.taskCount) return;
  const uint task = pc.taskBase + gl_GlobalInvocationID.x;
  const uint local = tasks[2u * task];
  const uint zy = tasks[2u * task + 1u];
  const RasterTet t = tets[local];
  const uint slabZ = zy & 0xFFFFu;
  const int z = int(pc.slabZ0 + slabZ);
  const int firstRow = int(zy >> 16);
  const int y1 = min(firstRow + VOX_RASTER_ROWS_PER_TASK - 1, t.hiY);
  for (int y = max(firstRow, t.loY); y <= y1; ++y) {
    int x0, x1;
    if (!rowSpan(t, y, z, x0, x1)) continue;
    const uint row = (slabZ * pc.latticeNy + uint(y)) * pc.latticeNx;
    for (int x = x0; x <= x1; ++x) atomicMin(state[row + uint(x)], local);
  }
}
