// Shading of a visible voxel, used by raycast.comp and mirrored by shadeRay
// (geometry/render/raycast_reference.cpp): its normal (unit, grid-frame
// axes, facing the camera: the smoothed occupancy's or the crossed face's,
// geometry/render/surface_normals.h) under a headlight from the camera and a
// fill light above and to the left of it, plus ambient. The headlight makes
// surfaces turned towards the viewer brightest, so a sphere darkens towards
// its rim; the fill light tells the three face orientations of a voxel apart.
// A depth cue darkens what lies farther along the view axis (depth: 0 at the
// scene's nearest corner, 1 at its farthest): a limb in front stands out,
// also where faces show no slope.

float surfaceShade(vec3 normal, vec3 headlight, vec3 fill, float ambient, float depth) {
  const float head = max(0.0, dot(normal, headlight));
  const float side = max(0.0, dot(normal, fill));
  const float light = min(1.0, ambient + (1.0 - ambient) * (VOX_SHADE_HEADLIGHT * head + VOX_SHADE_FILL * side));
  return light * (1.0 - VOX_SHADE_DEPTH * clamp(depth, 0.0, 1.0));
}
