#version 460
// Resolve stage, once per source window (CPU reference: resolveSamples in
// geometry/raster/rasterize.cpp): each task walks its tet's spans again and
// labels the samples its tet won: the source voxel nearest the sample's rest
// position (the tet's affine map, evaluated around its anchor so float keeps
// its precision), resolved to 0 off the source grid, left pending while its
// slice is outside the window. The window (two uint16 labels per word) spans
// kSourceParts storage bindings of 2^26 labels each.
#extension GL_GOOGLE_include_directive : require
#include "shared/interface.h"
#include "shared/lattice_span.glsl"
#include "shared/raster_tasks.glsl"

layout(constant_id = 0) const uint kSourceParts = 1;

layout(std430, binding = VOX_RASTER_BINDING_MAPS) readonly buffer Maps { RasterMap maps[]; };
layout(std430, binding = VOX_RASTER_BINDING_SOURCE + 0) readonly buffer Source0 { uint source0[]; };
layout(std430, binding = VOX_RASTER_BINDING_SOURCE + 1) readonly buffer Source1 { uint source1[]; };
layout(std430, binding = VOX_RASTER_BINDING_SOURCE + 2) readonly buffer Source2 { uint source2[]; };
layout(std430, binding = VOX_RASTER_BINDING_SOURCE + 3) readonly buffer Source3 { uint source3[]; };
layout(std430, binding = VOX_RASTER_BINDING_SOURCE + 4) readonly buffer Source4 { uint source4[]; };
layout(std430, binding = VOX_RASTER_BINDING_SOURCE + 5) readonly buffer Source5 { uint source5[]; };
layout(std430, binding = VOX_RASTER_BINDING_SOURCE + 6) readonly buffer Source6 { uint source6[]; };
layout(std430, binding = VOX_RASTER_BINDING_SOURCE + 7) readonly buffer Source7 { uint source7[]; };

uint windowLabel(uint index) {
  const uint part = index >> VOX_RASTER_SOURCE_PART_LABELS_LOG2;
  const uint w = (index & ((1u << VOX_RASTER_SOURCE_PART_LABELS_LOG2) - 1u)) >> 1;
  // Parts beyond kSourceParts are compiled out.
  uint word = source0[w];
  if (kSourceParts > 1u && part == 1u) word = source1[w];
  if (kSourceParts > 2u && part == 2u) word = source2[w];
  if (kSourceParts > 3u && part == 3u) word = source3[w];
  if (kSourceParts > 4u && part == 4u) word = source4[w];
  if (kSourceParts > 5u && part == 5u) word = source5[w];
  if (kSourceParts > 6u && part == 6u) word = source6[w];
  if (kSourceParts > 7u && part == 7u) word = source7[w];
  return (index & 1u) == 0u ? (word & 0xFFFFu) : (word >> 16);
}

void main() {
  Task task;
  RasterTet t;
  if (!taskOfInvocation(task, t)) return;
  const RasterMap m = maps[task.local];
  const vec3 lx = vec3(m.l00, m.l10, m.l20);
  const vec3 ly = vec3(m.l01, m.l11, m.l21);
  const vec3 lz = vec3(m.l02, m.l12, m.l22);
  const ivec3 whole = ivec3(m.sx, m.sy, m.sz);
  const ivec3 sourceDims = ivec3(pc.sourceNx, pc.sourceNy, pc.sourceNz);
  const vec3 slice = vec3(m.fx, m.fy, m.fz) + lz * float(task.z - m.az);
  for (int y = task.y0; y <= task.y1; ++y) {
    int x0, x1;
    if (!rowSpan(t, y, task.z, x0, x1)) continue;
    const uint row = rowStart(task, y);
    const vec3 base = slice + ly * float(y - m.ay);
    for (int x = x0; x <= x1; ++x) {
      const uint s = row + uint(x);
      if (state[s] != task.local) continue;
      const ivec3 v = whole + ivec3(floor(base + lx * float(x - m.ax) + 0.5));
      if (any(lessThan(v, ivec3(0))) || any(greaterThanEqual(v, sourceDims))) {
        state[s] = VOX_RASTER_RESOLVED;
      } else if (v.z >= int(pc.windowFirst) && v.z < int(pc.windowEnd)) {
        const uint index = (uint(v.z) - pc.windowFirst) * pc.sourceNx * pc.sourceNy + uint(v.y) * pc.sourceNx + uint(v.x);
        state[s] = VOX_RASTER_RESOLVED | windowLabel(index);
      }
    }
  }
}
