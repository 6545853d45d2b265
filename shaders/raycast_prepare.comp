#version 460
// Per-frame factors of eq. 5.1-5.2 for every deformed tet (CPU reference:
// tetFactors in geometry/render/raycast_scene.cpp). Relative to the anchor
// v0: lambda_k(p) = dot(delta_k n_k, p - v0) for k = 1..3, n_k the normal of
// the face opposite v_k, delta_k = 1 / dot(v_k - v0, n_k) = 1 / det.
#extension GL_GOOGLE_include_directive : require
#include "shared/interface.h"

layout(local_size_x = VOX_RAYCAST_PREPARE_GROUP_SIZE) in;

layout(std430, binding = VOX_RAYCAST_PREPARE_BINDING_TETS) readonly buffer Tets { uvec4 tets[]; };
layout(std430, binding = VOX_RAYCAST_PREPARE_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = VOX_RAYCAST_PREPARE_BINDING_FACTORS) writeonly buffer Factors { vec4 factors[]; };
layout(push_constant) uniform Push { RaycastPreparePush pc; };

void main() {
  const uint t = gl_GlobalInvocationID.x;
  if (t >= pc.tetCount) return;
  const uvec4 q = tets[t];
  const vec3 v0 = positions[q.x].xyz;
  const vec3 e1 = positions[q.y].xyz - v0;
  const vec3 e2 = positions[q.z].xyz - v0;
  const vec3 e3 = positions[q.w].xyz - v0;
  const vec3 n1 = cross(e2, e3), n2 = cross(e3, e1), n3 = cross(e1, e2);
  const float det = dot(e1, n1);
  if (!(abs(det) > VOX_RAYCAST_DEGENERATE_TET_RATIO * length(e1) * length(e2) * length(e3))) {
    // Contains no point: lambda_1..3 = -1.
    factors[4u * t + 0u] = vec4(0.0, 0.0, 0.0, -1.0);
    factors[4u * t + 1u] = vec4(0.0, 0.0, 0.0, -1.0);
    factors[4u * t + 2u] = vec4(0.0, 0.0, 0.0, -1.0);
  } else {
    const float delta = 1.0 / det;
    factors[4u * t + 0u] = vec4(delta * n1, 0.0);
    factors[4u * t + 1u] = vec4(delta * n2, 0.0);
    factors[4u * t + 2u] = vec4(delta * n3, 0.0);
  }
  factors[4u * t + 3u] = vec4(v0, 0.0);
}
