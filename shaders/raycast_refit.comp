#version 460
// Boxes of the boundary BVH for the deformed positions (CPU reference:
// refitBoundaryBvh in geometry/render/boundary_bvh.cpp; the host's float
// boxes: storeNode in gpu/kernels/raycast.cpp). One invocation per node of
// one level of the refit order: a leaf boxes its faces' vertices and pads the
// box so that it holds the ray caster's tolerant face test; an inner node
// joins its children's boxes, which the previous dispatch wrote.
#extension GL_GOOGLE_include_directive : require
#include "shared/interface.h"

layout(local_size_x = VOX_RAYCAST_REFIT_GROUP_SIZE) in;

layout(std430, binding = VOX_RAYCAST_REFIT_BINDING_NODES) buffer Nodes { RaycastNode nodes[]; };
layout(std430, binding = VOX_RAYCAST_REFIT_BINDING_FACES) readonly buffer Faces { uvec4 faces[]; };
layout(std430, binding = VOX_RAYCAST_REFIT_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = VOX_RAYCAST_REFIT_BINDING_ORDER) readonly buffer Order { uint order[]; };
layout(push_constant) uniform Push { RaycastRefitPush pc; };

// Relative step that moves a float outwards by at least one ulp after the
// rounding of the padding's subtraction and addition.
const float kOutward = 2.5e-7;

vec3 nodeLo(uint n) { return vec3(nodes[n].lo[0], nodes[n].lo[1], nodes[n].lo[2]); }
vec3 nodeHi(uint n) { return vec3(nodes[n].hi[0], nodes[n].hi[1], nodes[n].hi[2]); }

void main() {
  const uint i = gl_GlobalInvocationID.x;
  if (i >= pc.count) return;
  const uint n = order[pc.first + i];
  const int count = nodes[n].count;
  const int first = nodes[n].rightOrFirst;
  vec3 lo, hi;
  if (count > 0) {
    lo = vec3(3.0e38);
    hi = vec3(-3.0e38);
    for (int f = first; f < first + count; ++f) {
      const uvec4 face = faces[f];
      for (int k = 0; k < 3; ++k) {
        const vec3 p = positions[face[k]].xyz;
        lo = min(lo, p);
        hi = max(hi, p);
      }
    }
    const vec3 extent = hi - lo;
    const float pad = VOX_RAYCAST_REFIT_PAD + 2.0 * VOX_RAYCAST_FACE_HIT_TOLERANCE * max(extent.x, max(extent.y, extent.z));
    lo -= vec3(pad);
    hi += vec3(pad);
    lo -= abs(lo) * kOutward;
    hi += abs(hi) * kOutward;
  } else {
    // Children: the next node and `first` (the right child).
    lo = min(nodeLo(n + 1u), nodeLo(uint(first)));
    hi = max(nodeHi(n + 1u), nodeHi(uint(first)));
  }
  for (int a = 0; a < 3; ++a) {
    nodes[n].lo[a] = lo[a];
    nodes[n].hi[a] = hi[a];
  }
}
