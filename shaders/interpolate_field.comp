#version 460
// Field interpolation after the locate stage (CPU reference:
// geometry/deform/field_interpolation.cpp): the located tet's barycentric
// interpolation of the per-vertex values, as an affine map around an anchor
// lattice point; `fill` where no tet contains the point.
#extension GL_GOOGLE_include_directive : require
#include "shared/interface.h"

layout(local_size_x = VOX_RASTER_GROUP_SIZE) in;

layout(std430, binding = VOX_RASTER_BINDING_STATE) readonly buffer State { uint state[]; };
layout(std430, binding = VOX_RASTER_BINDING_MAPS) readonly buffer Maps { FieldMap maps[]; };
layout(std430, binding = VOX_RASTER_BINDING_OUTPUT) writeonly buffer Output { float values[]; };
layout(push_constant) uniform Push { FieldInterpolatePush pc; };

void main() {
  if (gl_GlobalInvocationID.x >= pc.itemCount) return;
  const uint s = pc.itemBase + gl_GlobalInvocationID.x;
  const uint st = state[s];
  if (st == VOX_RASTER_NO_TET) {
    values[s] = pc.fill;
    return;
  }
  const uint row = s / pc.latticeNx;
  const ivec3 q = ivec3(s % pc.latticeNx, row % pc.latticeNy, pc.slabZ0 + row / pc.latticeNy);
  const FieldMap m = maps[st];
  const vec3 d = vec3(q - ivec3(m.ax, m.ay, m.az));
  values[s] = m.value + (m.gx * d.x + m.gy * d.y + m.gz * d.z);
}
