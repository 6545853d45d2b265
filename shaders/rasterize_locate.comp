#version 460
// Locate stage (CPU reference: locateLatticePoints in
// geometry/raster/lattice_tets.cpp): each task walks its tet's scanline spans
// and claims their points by atomicMin of the slab-local tet index. Local
// indices ascend with the TM index, so every sample ends with the
// lowest-index tet whose closed test it passes, whatever the execution order.
#extension GL_GOOGLE_include_directive : require
#include "shared/interface.h"
#include "shared/lattice_span.glsl"
#include "shared/raster_tasks.glsl"

void main() {
  Task task;
  RasterTet t;
  if (!taskOfInvocation(task, t)) return;
  for (int y = task.y0; y <= task.y1; ++y) {
    int x0, x1;
    if (!rowSpan(t, y, task.z, x0, x1)) continue;
    const uint row = rowStart(task, y);
    for (int x = x0; x <= x1; ++x) atomicMin(state[row + uint(x)], task.local);
  }
}
