#version 460
// Entry buffer of the ray caster: rasterizes the front-facing boundary faces
// of the deformed transfer mesh. Each pixel gets the first face its ray
// enters through (smallest t, then lowest face index: the key order of
// firstEntryAfter in geometry/render/boundary_bvh.h) and how many front faces
// the ray crosses, so rays that cannot re-enter the mesh skip the BVH.
// Coverage is decided per pixel by the same ray / face test the ray caster
// uses; the projected triangle only bounds the pixels tried.
#extension GL_GOOGLE_include_directive : require
#include "shared/interface.h"

layout(local_size_x = VOX_RAYCAST_ENTRIES_GROUP_SIZE) in;

layout(std430, binding = VOX_RAYCAST_ENTRIES_BINDING_PARAMS) readonly buffer Params { RaycastParams P; };
layout(std430, binding = VOX_RAYCAST_ENTRIES_BINDING_FACES) readonly buffer Faces { uvec4 faces[]; };
layout(std430, binding = VOX_RAYCAST_ENTRIES_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = VOX_RAYCAST_ENTRIES_BINDING_ENTRIES) buffer Entries { uint entries[]; };
layout(std430, binding = VOX_RAYCAST_ENTRIES_BINDING_TILE_FLAGS) buffer TileFlags { uint tileFlags[]; };
layout(std430, binding = VOX_RAYCAST_ENTRIES_BINDING_TILES) buffer Tiles { uint tiles[]; };
layout(std430, binding = VOX_RAYCAST_ENTRIES_BINDING_DISPATCH) buffer Dispatch { uint dispatchSize[]; };
layout(push_constant) uniform Push { RaycastEntriesPush pc; };

#include "shared/raycast.glsl"

// Depth (t) below which a triangle is clipped away: hits need t >= 0.
const float kNearDepth = VOX_RAYCAST_NEAR_DEPTH;
// Pixels of slack around a face's projected bounds.
const float kPixelSlack = 0.05;

// Camera coordinates (t, t sx, t sy) of a render-frame point.
vec3 toCamera(vec3 p) {
  const vec3 q = p - vec3Of(P.eye);
  return vec3(dot(vec3(P.toCamera[0], P.toCamera[1], P.toCamera[2]), q), dot(vec3(P.toCamera[4], P.toCamera[5], P.toCamera[6]), q),
              dot(vec3(P.toCamera[8], P.toCamera[9], P.toCamera[10]), q));
}

void main() {
  const uint f = gl_GlobalInvocationID.x;
  if (f >= pc.faceCount) return;
  const uvec4 face = faces[f];
  const vec3 a = positions[face.x].xyz, b = positions[face.y].xyz, c = positions[face.z].xyz;
  const vec3 eye = vec3Of(P.eye);
  // A face seen from behind is back-facing for every ray through it.
  if (dot(a - eye, cross(b - a, c - a)) > 0.0) return;

  // Clip the triangle to t >= kNearDepth (Sutherland-Hodgman, one plane) and
  // bound its projection.
  const vec3 k[3] = vec3[3](toCamera(a), toCamera(b), toCamera(c));
  vec2 lo = vec2(kInf), hi = vec2(-kInf);
  bool any = false;
  for (int i = 0; i < 3; ++i) {
    const vec3 p = k[i], q = k[(i + 1) % 3];
    if (p.x >= kNearDepth) {
      lo = min(lo, p.yz / p.x);
      hi = max(hi, p.yz / p.x);
      any = true;
    }
    if ((p.x >= kNearDepth) != (q.x >= kNearDepth)) {
      const vec3 m = mix(p, q, (kNearDepth - p.x) / (q.x - p.x));
      lo = min(lo, m.yz / kNearDepth);
      hi = max(hi, m.yz / kNearDepth);
      any = true;
    }
  }
  if (!any) return;
  // Image-plane offsets (sx, sy) to continuous pixel coordinates (pixel
  // centres at integers); the pixels whose centres lie in the bounds, with
  // kPixelSlack for rounding and the face test's tolerance.
  const float sxScale = P.tanHalfFovY * P.aspect;
  const float x0 = ceil((lo.x / sxScale + 1.0) * 0.5 * float(P.width) - 0.5 - kPixelSlack);
  const float x1 = floor((hi.x / sxScale + 1.0) * 0.5 * float(P.width) - 0.5 + kPixelSlack);
  const float y0 = ceil((1.0 - hi.y / P.tanHalfFovY) * 0.5 * float(P.height) - 0.5 - kPixelSlack);
  const float y1 = floor((1.0 - lo.y / P.tanHalfFovY) * 0.5 * float(P.height) - 0.5 + kPixelSlack);
  if (x1 < 0.0 || y1 < 0.0 || x0 > float(P.width - 1u) || y0 > float(P.height - 1u) || x0 > x1 || y0 > y1) return;
  const uint px0 = uint(max(x0, 0.0)), px1 = uint(min(x1, float(P.width - 1u)));
  const uint py0 = uint(max(y0, 0.0)), py1 = uint(min(y1, float(P.height - 1u)));

  // The bounded pixels in row order; work group row gl_WorkGroupID.y takes
  // its chunk of VOX_RAYCAST_ENTRIES_CHUNK_PIXELS of them.
  const uint columns = px1 - px0 + 1u;
  if (pc.pass == 2u) {
    const uint pixels = columns * (py1 - py0 + 1u);
    const uint chunks = (pixels + VOX_RAYCAST_ENTRIES_CHUNK_PIXELS - 1u) / VOX_RAYCAST_ENTRIES_CHUNK_PIXELS;
    atomicMax(dispatchSize[VOX_RAYCAST_DISPATCH_ENTRIES + 1], chunks);
    return;
  }
  const uint first = gl_WorkGroupID.y * VOX_RAYCAST_ENTRIES_CHUNK_PIXELS;
  const uint last = min(first + VOX_RAYCAST_ENTRIES_CHUNK_PIXELS, columns * (py1 - py0 + 1u));
  const uint plane = P.width * P.height;
  const uint tilesX = (P.width + VOX_RAYCAST_GROUP_X - 1u) / VOX_RAYCAST_GROUP_X;
  for (uint i = first; i < last; ++i) {
    const uint x = px0 + i % columns, y = py0 + i / columns;
    float t;
    if (!rayFrontFace(eye, pixelDirection(uvec2(x, y)), a, b, c, t) || !(t >= 0.0)) continue;
    const uint pixel = y * P.width + x;
    if (pc.pass == 0u) {
      atomicMin(entries[pixel], floatBitsToUint(t));
      atomicAdd(entries[2u * plane + pixel], 1u);
      // The first hit of a tile appends it to the list and grows the ray
      // pass's dispatch to hold it.
      const uint tile = (y / VOX_RAYCAST_GROUP_Y) * tilesX + x / VOX_RAYCAST_GROUP_X;
      if (tileFlags[tile] == 0u && atomicExchange(tileFlags[tile], 1u) == 0u) {
        const uint slot = atomicAdd(tiles[0], 1u);
        tiles[1u + slot] = tile;
        atomicMax(dispatchSize[VOX_RAYCAST_DISPATCH_RAYS], min(slot + 1u, pc.maxGroupsX));
        atomicMax(dispatchSize[VOX_RAYCAST_DISPATCH_RAYS + 1], slot / pc.maxGroupsX + 1u);
      }
    } else if (floatBitsToUint(t) == entries[pixel]) {
      atomicMin(entries[plane + pixel], f);
    }
  }
}
