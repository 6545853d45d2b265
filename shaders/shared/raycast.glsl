// GLSL shared by raycast.comp and raycast_entries.comp: the pixel ray and the
// ray / boundary-face test. `precise` forbids contracting their arithmetic
// differently in the two shaders, so both passes compute bit-identical hits.
// Included after the RaycastParams block named P.
#ifndef VOXMORPH_RAYCAST_GLSL
#define VOXMORPH_RAYCAST_GLSL

const float kFaceHitTolerance = VOX_RAYCAST_FACE_HIT_TOLERANCE;
const float kInf = 1e30;

vec3 vec3Of(float v[4]) { return vec3(v[0], v[1], v[2]); }

// Ray direction of pixel (x, y) in the render frame (CameraRays::sx, sy).
vec3 pixelDirection(uvec2 px) {
  precise const float sx = (2.0 * (float(px.x) + 0.5) / float(P.width) - 1.0) * P.tanHalfFovY * P.aspect;
  precise const float sy = (1.0 - 2.0 * (float(px.y) + 0.5) / float(P.height)) * P.tanHalfFovY;
  precise const vec3 d = vec3Of(P.forward) + sx * vec3Of(P.right) + sy * vec3Of(P.up);
  return d;
}

// Moller-Trumbore, front faces only (det > 0 means dot(d, n) < 0), with the
// barycentric tolerance that makes rays through shared edges hit both faces.
bool rayFrontFace(vec3 o, vec3 d, vec3 a, vec3 b, vec3 c, out float t) {
  t = 0.0;
  precise const vec3 e1 = b - a, e2 = c - a;
  precise const vec3 p = cross(d, e2);
  precise const float det = dot(e1, p);
  if (!(det > 0.0)) return false;
  precise const float inv = 1.0 / det;
  precise const vec3 s = o - a;
  precise const float u = dot(s, p) * inv;
  if (u < -kFaceHitTolerance || u > 1.0 + kFaceHitTolerance) return false;
  precise const vec3 q = cross(s, e1);
  precise const float v = dot(d, q) * inv;
  if (v < -kFaceHitTolerance || u + v > 1.0 + kFaceHitTolerance) return false;
  precise const float hit = dot(e2, q) * inv;
  t = hit;
  return true;
}

#endif
