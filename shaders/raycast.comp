#version 460
// Transfer-mesh-guided voxel ray casting (thesis chapter 5), one invocation
// per pixel. The algorithm, step by step, and its limitation are described in
// geometry/render/raycast_reference.h, the CPU reference this mirrors.
#extension GL_GOOGLE_include_directive : require
#include "shared/interface.h"

layout(local_size_x = VOX_RAYCAST_GROUP_X, local_size_y = VOX_RAYCAST_GROUP_Y) in;

layout(std430, binding = VOX_RAYCAST_BINDING_PARAMS) readonly buffer Params { RaycastParams P; };
layout(std430, binding = VOX_RAYCAST_BINDING_NODES) readonly buffer Nodes { RaycastNode nodes[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_FACES) readonly buffer Faces { uvec4 faces[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_POSITIONS) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_FACTORS) readonly buffer Factors { vec4 factors[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_NEIGHBORS) readonly buffer Neighbors { ivec4 neighbors[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_REST) readonly buffer Rest { vec4 rest[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_PALETTE) readonly buffer Palette { uint palette[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_ENTRIES) readonly buffer Entries { uint entries[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_IMAGE) writeonly buffer Image { uint image[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_TILES) readonly buffer Tiles { uint tiles[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_SLAB0 + 0) readonly buffer Slab0 { uint slab0[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_SLAB0 + 1) readonly buffer Slab1 { uint slab1[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_SLAB0 + 2) readonly buffer Slab2 { uint slab2[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_SLAB0 + 3) readonly buffer Slab3 { uint slab3[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_SLAB0 + 4) readonly buffer Slab4 { uint slab4[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_SLAB0 + 5) readonly buffer Slab5 { uint slab5[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_SLAB0 + 6) readonly buffer Slab6 { uint slab6[]; };
layout(std430, binding = VOX_RAYCAST_BINDING_SLAB0 + 7) readonly buffer Slab7 { uint slab7[]; };

#include "shared/raycast.glsl"
#include "shared/shading.glsl"

// ---------------------------------------------------------------- entry faces

bool rayBox(vec3 o, vec3 inv, vec3 lo, vec3 hi, out float tNear, out float tFar) {
  const vec3 t0 = (lo - o) * inv, t1 = (hi - o) * inv;
  const vec3 mn = min(t0, t1), mx = max(t0, t1);
  tNear = max(max(mn.x, mn.y), mn.z);
  tFar = min(min(mx.x, mx.y), mx.z);
  return tNear <= tFar;
}

// The front face hit at the smallest key (t, face) greater than (afterT,
// afterFace); face -1 when none.
void firstEntryAfter(vec3 o, vec3 d, float afterT, int afterFace, out float bestT, out int bestFace) {
  bestT = kInf;
  bestFace = -1;
  vec3 inv;
  for (int a = 0; a < 3; ++a) inv[a] = 1.0 / (d[a] != 0.0 ? d[a] : 1e-30);
  int stack[VOX_RAYCAST_BVH_STACK];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const int ni = stack[--top];
    const RaycastNode n = nodes[ni];
    float tn, tf;
    if (!rayBox(o, inv, vec3(n.lo[0], n.lo[1], n.lo[2]), vec3(n.hi[0], n.hi[1], n.hi[2]), tn, tf) || tf < afterT || tn > bestT)
      continue;
    if (n.count > 0) {
      for (int f = n.rightOrFirst; f < n.rightOrFirst + n.count; ++f) {
        const uvec4 face = faces[f];
        float t;
        if (!rayFrontFace(o, d, positions[face.x].xyz, positions[face.y].xyz, positions[face.z].xyz, t)) continue;
        const bool after = t > afterT || (t == afterT && f > afterFace);
        const bool better = t < bestT || (t == bestT && f < bestFace);
        if (after && better) {
          bestT = t;
          bestFace = f;
        }
      }
    } else if (top + 2 <= VOX_RAYCAST_BVH_STACK) {
      stack[top++] = n.rightOrFirst;
      stack[top++] = ni + 1;
    }
  }
}

// --------------------------------------------------------- point location

// The tet a ray is in, with its factors, neighbours and rest frame held in
// registers: consecutive cells mostly lie in the same tet, and reloading
// them for every cell would dominate the cost of a step.
struct TetCache {
  int tet;
  vec4 f1, f2, f3, anchor;
  ivec4 nb;
};

void loadTet(inout TetCache c, int tet) {
  if (c.tet == tet) return;
  c.tet = tet;
  c.f1 = factors[4 * tet + 0];
  c.f2 = factors[4 * tet + 1];
  c.f3 = factors[4 * tet + 2];
  c.anchor = factors[4 * tet + 3];
  c.nb = neighbors[tet];
}

// Visibility walk (thesis 5.2.3): true when `tet` ends on a tet containing p.
bool locate(vec3 p, inout int tet, inout TetCache c, out vec4 lambda) {
  lambda = vec4(0.0);
  for (uint s = 0u; s < P.maxWalkSteps; ++s) {
    loadTet(c, tet);
    const vec3 q = p - c.anchor.xyz;
    lambda.y = dot(c.f1.xyz, q) + c.f1.w;
    lambda.z = dot(c.f2.xyz, q) + c.f2.w;
    lambda.w = dot(c.f3.xyz, q) + c.f3.w;
    lambda.x = 1.0 - lambda.y - lambda.z - lambda.w;
    const bvec4 outside = lessThan(lambda, vec4(-VOX_RAYCAST_INSIDE_TOLERANCE));
    if (!any(outside)) return true;
    // Cross the face with the most negative coordinate among those with a
    // neighbour (the mesh may be non-convex); ties go to the lowest index.
    const ivec4 nb = c.nb;
    const bvec4 crossable = bvec4(uvec4(outside) & uvec4(greaterThanEqual(nb, ivec4(0))));
    const vec4 m4 = mix(vec4(kInf), lambda, crossable);
    int next = nb.x;
    float m = m4.x;
    if (m4.y < m) {
      m = m4.y;
      next = nb.y;
    }
    if (m4.z < m) {
      m = m4.z;
      next = nb.z;
    }
    if (m4.w < m) {
      m = m4.w;
      next = nb.w;
    }
    if (m == kInf) return false;
    tet = next;
  }
  return false;
}

uint slabWord(uint slab, uint word) {
  switch (slab) {
    case 0u: return slab0[word];
    case 1u: return slab1[word];
    case 2u: return slab2[word];
    case 3u: return slab3[word];
    case 4u: return slab4[word];
    case 5u: return slab5[word];
    case 6u: return slab6[word];
    default: return slab7[word];
  }
}

// Label of source voxel v; 0 outside the grid.
uint labelAt(ivec3 v) {
  if (any(lessThan(v, ivec3(0))) || any(greaterThanEqual(v, ivec3(P.sourceDims[0], P.sourceDims[1], P.sourceDims[2])))) return 0u;
  const uint slab = uint(v.z) / P.slabSlices;
  const uint local = uint(v.x) + uint(P.sourceDims[0]) * uint(v.y) + P.sliceVoxels * (uint(v.z) - slab * P.slabSlices);
  const uint word = slabWord(slab, local >> 1);
  return (local & 1u) == 0u ? (word & 0xFFFFu) : (word >> 16);
}

ivec3 sourceShift() { return ivec3(P.sourceShift[0], P.sourceShift[1], P.sourceShift[2]); }

// Rest coordinate (shifted source index space) of the point with barycentric
// coordinates lambda in `tet`.
vec3 restPoint(int tet, vec3 lambda) {
  const vec4 a = rest[3 * tet + 0], b = rest[3 * tet + 1], c = rest[3 * tet + 2];
  return vec3(a.w, b.w, c.w) + lambda.x * a.xyz + lambda.y * b.xyz + lambda.z * c.xyz;
}

// Label of the source voxel the barycentric map sends the point to.
uint fetchLabel(int tet, vec4 lambda) { return labelAt(ivec3(floor(restPoint(tet, lambda.yzw) + 0.5)) + sourceShift()); }

bool visible(uint label) { return label != 0u && label < P.labelCount && (palette[label] >> 24) != 0u; }

// ---------------------------------------------------------------------- DDA
// Thesis Algorithm 2 over unit cells centred on integers; face crossings are
// recomputed from the integer cell, so no error accumulates.

struct Dda {
  vec3 e, d, inv;
  vec3 step;  // +-1, or 0 where the ray is parallel to the axis
  vec3 cell;  // integer values
  float tEnter;
  int axis;   // axis of the face through which the ray entered `cell`
};

vec3 ddaNext(Dda s) { return mix(vec3(kInf), (s.cell + 0.5 * s.step - s.e) * s.inv, notEqual(s.step, vec3(0.0))); }
float ddaExit(Dda s) {
  const vec3 t = ddaNext(s);
  return min(min(t.x, t.y), t.z);
}

void ddaStart(inout Dda s, float t0) {
  s.cell = floor(s.e + t0 * s.d + 0.5);
  s.tEnter = t0;
  // The face crossed last before t0 is the one the ray entered through.
  const vec3 prev = mix(vec3(-kInf), (s.cell - 0.5 * s.step - s.e) * s.inv, notEqual(s.step, vec3(0.0)));
  s.axis = 0;
  float last = prev.x;
  if (prev.y > last) {
    last = prev.y;
    s.axis = 1;
  }
  if (prev.z > last) s.axis = 2;
}

void ddaAdvance(inout Dda s) {
  const vec3 t = ddaNext(s);
  int a = 0;
  float ta = t.x;
  if (t.y < ta) {
    ta = t.y;
    a = 1;
  }
  if (t.z < ta) {
    ta = t.z;
    a = 2;
  }
  s.cell += s.step * vec3(equal(ivec3(a), ivec3(0, 1, 2)));
  s.tEnter = ta;
  s.axis = a;
}

// ---------------------------------------------------------------------- ray

// Cells whose centres are inside the TM can be crossed before the entry
// point, by up to half a cell diagonal away from the entry face's plane:
// along a ray that meets the face at a grazing angle, that is far.
float entryMargin(int face, vec3 d, float margin) {
  const uvec4 f = faces[face];
  const vec3 a = positions[f.x].xyz;
  const vec3 n = cross(positions[f.y].xyz - a, positions[f.z].xyz - a);
  const float grazing = abs(dot(n, d));  // |n . d| / |n| = |cos| |d|
  if (!(grazing > 0.0)) return VOX_RAYCAST_MAX_ENTRY_MARGIN_CELLS * margin;
  return min(VOX_RAYCAST_MAX_ENTRY_MARGIN_CELLS * margin, 0.5 * sqrt(3.0) * length(n) / grazing);
}

struct Hit {
  bool hit;
  uint label;
  int axis;
  int step;
  float t;     // ray parameter of the visible cell's entry (depth along the view axis, mm)
  vec3 cell;   // the visible cell
  vec3 point;  // where the ray enters it
  int tet;     // the tet containing its centre
};

Hit trace(vec3 e, vec3 d, uint pixel) {
  Hit res = Hit(false, 0u, 0, 0, 0.0, vec3(0.0), vec3(0.0), -1);
  // 1. Clip to the cells of G' and to the kept side of the cutting planes.
  float tLo = 0.0, tHi = kInf;
  const vec3 lo = vec3Of(P.cellsLo), hi = vec3Of(P.cellsHi);
  for (int a = 0; a < 3; ++a) {
    if (d[a] != 0.0) {
      float t0 = (lo[a] - e[a]) / d[a], t1 = (hi[a] - e[a]) / d[a];
      if (t0 > t1) {
        const float tmp = t0;
        t0 = t1;
        t1 = tmp;
      }
      tLo = max(tLo, t0);
      tHi = min(tHi, t1);
    } else if (e[a] < lo[a] || e[a] > hi[a]) {
      return res;
    }
  }
  for (uint c = 0u; c < VOX_RAYCAST_MAX_CUTS; ++c) {
    if (c >= P.cutCount) break;
    const vec3 n = vec3(P.cuts[4 * c], P.cuts[4 * c + 1], P.cuts[4 * c + 2]);
    const float nd = dot(n, d);
    const float bound = P.cuts[4 * c + 3] + 0.5 * (abs(n.x) + abs(n.y) + abs(n.z)) - dot(n, e);
    if (nd > 0.0) tHi = min(tHi, bound / nd);
    else if (nd < 0.0) tLo = max(tLo, bound / nd);
    else if (bound < 0.0) return res;
  }
  if (!(tLo <= tHi)) return res;

  // 2. First entry into the deformed TM, from the entry buffer. A ray that
  // crosses a single front face cannot re-enter the mesh: no BVH query.
  const uint plane = P.width * P.height;
  const uint frontFaces = entries[2u * plane + pixel];
  if (frontFaces == 0u) return res;
  float keyT = uintBitsToFloat(entries[pixel]);
  int keyFace = int(entries[plane + pixel]);
  const float margin = 0.5 * sqrt(3.0) / length(d);
  int tet = int(faces[keyFace].w);
  uint entryCount = 1u;
  float nextT = kInf;
  int nextFace = -1;
  bool nextKnown = frontFaces == 1u;
  float failStart = kInf;
  TetCache cache;
  cache.tet = -1;

  // 3. Cells in ray order. The BVH query for the next entry is hoisted out
  // of the cell loop: a cell that needs one leaves the loop, the query runs
  // once, and the cell is processed again from the same tet, with the same
  // result up to the point where the answer is needed. One query site keeps
  // the loop small, which matters on SIMD CPU drivers that execute every
  // branch masked.
  Dda dda;
  dda.e = e;
  dda.d = d;
  dda.step = sign(d);
  dda.inv = mix(vec3(0.0), 1.0 / d, notEqual(d, vec3(0.0)));
  dda.axis = 0;
  ddaStart(dda, max(keyT - entryMargin(keyFace, d, margin), tLo));
  uint cells = 0u;
  for (uint round = 0u; round <= P.maxEntries + 1u; ++round) {
    if (!nextKnown && round > 0u) {
      firstEntryAfter(e, d, keyT, keyFace, nextT, nextFace);
      nextKnown = true;
    }
    bool needQuery = false;
    while (cells < P.maxCells && dda.tEnter <= tHi) {
      const vec3 c = dda.cell;
      // Constant trip counts unroll: lavapipe ends an invocation after 65535
      // loop iterations, so per-cell loops are kept to the walk.
      bool removed = false;
      for (uint k = 0u; k < VOX_RAYCAST_MAX_CUTS; ++k)
        removed = removed || (k < P.cutCount && dot(vec3(P.cuts[4 * k], P.cuts[4 * k + 1], P.cuts[4 * k + 2]), c) > P.cuts[4 * k + 3]);
      if (!removed) {
        vec4 lambda;
        bool found = false, rayInside = false;
        const float mid = 0.5 * (dda.tEnter + ddaExit(dda));
        for (;;) {
          const int start = tet;
          found = locate(c, tet, cache, lambda);
          if (found) break;
          // 4. The walk left the mesh. If the ray itself is inside the mesh
          // in this cell, the centre is outside (the ray grazes the surface)
          // or across a concavity from where the walk went: walk along the
          // ray into the cell first, then to the centre.
          int rayTet = start;
          if (mid > keyT && locate(e + mid * d, rayTet, cache, lambda)) {
            rayInside = true;
            tet = rayTet;
            found = locate(c, rayTet, cache, lambda);
            if (found) tet = rayTet;
            break;
          }
          // The ray is outside: retry from the next entry face once the ray
          // has (almost) reached it.
          if (dda.tEnter <= keyT) break;
          if (!nextKnown) {
            tet = start;  // the cell is processed again, identically, after the query
            needQuery = true;
            break;
          }
          if (nextFace < 0 || nextT - entryMargin(nextFace, d, margin) > ddaExit(dda) || entryCount >= P.maxEntries) break;
          keyT = nextT;
          keyFace = nextFace;
          tet = int(faces[keyFace].w);
          nextKnown = false;
          failStart = kInf;
          ++entryCount;
        }
        if (needQuery) break;
        if (found) {
          failStart = kInf;
          const uint label = fetchLabel(tet, lambda);
          if (visible(label)) {
            res.hit = true;
            res.label = label;
            res.axis = dda.axis;
            res.step = int(dda.step[dda.axis]);
            res.t = dda.tEnter;
            res.cell = c;
            res.point = e + dda.tEnter * d;
            res.tet = tet;
            return res;
          }
        } else if (rayInside) {
          // A cell counts as outside only when the ray is outside in it, past
          // the entry point (before it, in the margin, failures are expected).
          failStart = kInf;
        } else if (failStart == kInf && dda.tEnter > keyT) {
          failStart = dda.tEnter;
        }
      }
      ++cells;
      if (failStart != kInf && ddaExit(dda) > max(failStart, keyT) + 2.0 * margin) {
        // Outside the mesh for two cells: jump to the next entry, if any.
        if (!nextKnown) {
          --cells;
          needQuery = true;
          break;
        }
        if (nextFace < 0 || entryCount >= P.maxEntries) return res;
        if (nextT - entryMargin(nextFace, d, margin) > ddaExit(dda)) {
          keyT = nextT;
          keyFace = nextFace;
          tet = int(faces[keyFace].w);
          nextKnown = false;
          failStart = kInf;
          ++entryCount;
          ddaStart(dda, keyT - entryMargin(keyFace, d, margin));
          continue;
        }
      }
      ddaAdvance(dda);
    }
    if (!needQuery) return res;
  }
  return res;
}

// ------------------------------------------------------------------ normals
// geometry/render/surface_normals.h: the equations and the choices at
// cutting planes and flat occupancy.

// Occupancy (1 where the label is visible) of the voxels (x, y), (x + 1, y),
// (x, y + 1), (x + 1, y + 1) of slice z, v = (x, y, z): one slab lookup for
// the four.
vec4 quadOccupancy(ivec3 v) {
  const ivec3 dims = ivec3(P.sourceDims[0], P.sourceDims[1], P.sourceDims[2]);
  vec4 o = vec4(0.0);
  if (v.z < 0 || v.z >= dims.z) return o;
  const uint slab = uint(v.z) / P.slabSlices;
  const uint sliceBase = P.sliceVoxels * (uint(v.z) - slab * P.slabSlices);
  for (int c = 0; c < 4; ++c) {
    const ivec2 xy = v.xy + ivec2(c & 1, c >> 1);
    if (any(lessThan(xy, ivec2(0))) || any(greaterThanEqual(xy, dims.xy))) continue;
    const uint local = sliceBase + uint(xy.x) + uint(dims.x) * uint(xy.y);
    const uint word = slabWord(slab, local >> 1);
    o[c] = visible((local & 1u) == 0u ? (word & 0xFFFFu) : (word >> 16)) ? 1.0 : 0.0;
  }
  return o;
}

// S(s): the occupancy of the visible labels interpolated trilinearly
// between voxel centres.
float smoothedOccupancy(vec3 s) {
  const vec3 base = floor(s);
  const vec3 f = s - base;
  const ivec3 v0 = ivec3(base) + sourceShift();
  const vec4 xy = vec4((1.0 - f.x) * (1.0 - f.y), f.x * (1.0 - f.y), (1.0 - f.x) * f.y, f.x * f.y);
  return (1.0 - f.z) * dot(quadOccupancy(v0), xy) + f.z * dot(quadOccupancy(v0 + ivec3(0, 0, 1)), xy);
}

// Gradient of the smoothed occupancy at rest point s: 3x3x3 samples of S
// P.differenceSteps apart, Sobel weights.
vec3 occupancyGradient(vec3 s) {
  const vec3 h = vec3Of(P.differenceSteps);
  vec3 g = vec3(0.0);
  for (int k = -1; k <= 1; ++k)
    for (int j = -1; j <= 1; ++j)
      for (int i = -1; i <= 1; ++i) {
        if (i == 0 && j == 0 && k == 0) continue;
        const vec3 o = vec3(i, j, k);
        const vec3 w = 2.0 - abs(o);
        g += smoothedOccupancy(s + o * h) * vec3(o.x * w.y * w.z, w.x * o.y * w.z, w.x * w.y * o.z);
      }
  return g / (32.0 * h);
}

// Unit normal (grid-frame axes, facing the camera) of the surface h shows.
vec3 surfaceNormal(Hit h) {
  vec3 face = vec3(0.0);
  face[h.axis] = -float(h.step);
  if (P.smoothNormals == 0u || h.tet < 0) return face;
  const vec3 spacing = vec3Of(P.cellSize);
  // The ray came through a removed cell: the cut face is flat.
  vec3 before = h.cell;
  before[h.axis] -= float(h.step);
  for (uint k = 0u; k < VOX_RAYCAST_MAX_CUTS; ++k) {
    if (k >= P.cutCount) break;
    const vec3 n = vec3(P.cuts[4 * k], P.cuts[4 * k + 1], P.cuts[4 * k + 2]);
    if (dot(n, before) > P.cuts[4 * k + 3]) return normalize(n / spacing);
  }
  const vec4 f1 = factors[4 * h.tet + 0], f2 = factors[4 * h.tet + 1], f3 = factors[4 * h.tet + 2];
  const vec3 q = h.point - factors[4 * h.tet + 3].xyz;
  const vec3 lambda = vec3(dot(f1.xyz, q) + f1.w, dot(f2.xyz, q) + f2.w, dot(f3.xyz, q) + f3.w);
  const vec3 gs = occupancyGradient(restPoint(h.tet, lambda));
  if (!(length(gs) >= VOX_RAYCAST_FLAT_OCCUPANCY_GRADIENT)) return face;
  // grad_p = L^T R^T grad_s: R's columns are the rest edges, L's rows the planes.
  const vec3 rg = vec3(dot(rest[3 * h.tet + 0].xyz, gs), dot(rest[3 * h.tet + 1].xyz, gs), dot(rest[3 * h.tet + 2].xyz, gs));
  const vec3 gx = (rg.x * f1.xyz + rg.y * f2.xyz + rg.z * f3.xyz) / spacing;
  if (!(length(gx) > 0.0)) return face;
  vec3 n = -normalize(gx);
  if (dot(n, (h.point - vec3Of(P.eye)) * spacing) > 0.0) n = -n;
  return n;
}

uint shade(Hit h) {
  if (!h.hit) return P.background;
  const float depth = P.depthFar > P.depthNear ? (h.t - P.depthNear) / (P.depthFar - P.depthNear) : 0.0;
  const float s = surfaceShade(surfaceNormal(h), vec3Of(P.headlight), vec3Of(P.light), P.ambient, depth);
  const uint albedo = palette[h.label];
  const vec3 c = vec3(float(albedo & 0xFFu), float((albedo >> 8) & 0xFFu), float((albedo >> 16) & 0xFFu));
  const uvec3 q = uvec3(min(vec3(255.0), floor(c * s + 0.5)));
  return q.r | (q.g << 8) | (q.b << 16) | 0xFF000000u;
}

void main() {
  const uint tilesX = (P.width + VOX_RAYCAST_GROUP_X - 1u) / VOX_RAYCAST_GROUP_X;
  const uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
  if (group >= tiles[0]) return;
  const uint tile = tiles[1u + group];
  const uvec2 px = uvec2(tile % tilesX, tile / tilesX) * uvec2(VOX_RAYCAST_GROUP_X, VOX_RAYCAST_GROUP_Y) + gl_LocalInvocationID.xy;
  if (px.x >= P.width || px.y >= P.height) return;
  const uint pixel = px.y * P.width + px.x;
  // A ray that crosses no front face keeps the background.
  if (entries[2u * P.width * P.height + pixel] == 0u) return;
  image[pixel] = shade(trace(vec3Of(P.eye), pixelDirection(px), pixel));
}
