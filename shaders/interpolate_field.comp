#version 460
// Field interpolation after the locate stage (CPU reference:
// geometry/raster/field_interpolation.cpp): each task walks its tet's spans
// and writes, at the points its tet won, the tet's barycentric interpolation
// of the per-vertex values (an affine map around an anchor lattice point).
// Points no tet won keep the fill value the host wrote.
#extension GL_GOOGLE_include_directive : require
#include "shared/interface.h"
#include "shared/lattice_span.glsl"
#include "shared/raster_tasks.glsl"

layout(std430, binding = VOX_RASTER_BINDING_MAPS) readonly buffer Maps { FieldMap maps[]; };
layout(std430, binding = VOX_FIELD_BINDING_OUTPUT) writeonly buffer Output { float values[]; };

void main() {
  Task task;
  RasterTet t;
  if (!taskOfInvocation(task, t)) return;
  const FieldMap m = maps[task.local];
  const float slice = m.value + m.gz * float(task.z - m.az);
  for (int y = task.y0; y <= task.y1; ++y) {
    int x0, x1;
    if (!rowSpan(t, y, task.z, x0, x1)) continue;
    const uint row = rowStart(task, y);
    const float base = slice + m.gy * float(y - m.ay);
    for (int x = x0; x <= x1; ++x)
      if (state[row + uint(x)] == task.local) values[row + uint(x)] = base + m.gx * float(x - m.ax);
  }
}
