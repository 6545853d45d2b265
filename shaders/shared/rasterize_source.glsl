// Resolve a located sample to its source label (CPU reference:
// resolveSamples in geometry/deform/rasterize.cpp). The including shader
// declares `pc` as RasterResolvePush. The source window (slices
// [windowFirst, windowEnd), two uint16 labels per word) is bound as
// VOX_RASTER_SOURCE_PARTS storage buffers of 2^26 labels each, so one window
// can exceed a single binding's 128 MiB.

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
  uint word;
  switch (part) {
    case 0u: word = source0[w]; break;
    case 1u: word = source1[w]; break;
    case 2u: word = source2[w]; break;
    case 3u: word = source3[w]; break;
    case 4u: word = source4[w]; break;
    case 5u: word = source5[w]; break;
    case 6u: word = source6[w]; break;
    default: word = source7[w]; break;
  }
  return (index & 1u) == 0u ? (word & 0xFFFFu) : (word >> 16);
}

// New state of a sample at lattice point q: resolved with the window's label,
// resolved to 0 off the source grid, or unchanged (no tet, already resolved,
// or a source slice outside the window).
uint resolveSample(uint st, ivec3 q) {
  if ((st & VOX_RASTER_RESOLVED) != 0u) return st;
  const RasterMap m = maps[st];
  const vec3 d = vec3(q - ivec3(m.ax, m.ay, m.az));
  const vec3 u = vec3(m.fx + (m.l00 * d.x + m.l01 * d.y + m.l02 * d.z),
                      m.fy + (m.l10 * d.x + m.l11 * d.y + m.l12 * d.z),
                      m.fz + (m.l20 * d.x + m.l21 * d.y + m.l22 * d.z));
  const ivec3 v = ivec3(m.sx, m.sy, m.sz) + ivec3(floor(u + 0.5));
  if (any(lessThan(v, ivec3(0))) || v.x >= int(pc.sourceNx) || v.y >= int(pc.sourceNy) || v.z >= int(pc.sourceNz))
    return VOX_RASTER_RESOLVED;
  if (v.z < int(pc.windowFirst) || v.z >= int(pc.windowEnd)) return st;
  const uint index = (uint(v.z) - pc.windowFirst) * pc.sourceNx * pc.sourceNy + uint(v.y) * pc.sourceNx + uint(v.x);
  return VOX_RASTER_RESOLVED | windowLabel(index);
}

uint sampleLabel(uint st) { return (st & VOX_RASTER_RESOLVED) != 0u && st != VOX_RASTER_NO_TET ? (st & 0xFFFFu) : 0u; }
