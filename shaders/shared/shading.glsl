// Shading of a visible voxel face, used by raycast.comp and mirrored by
// shadeRay (geometry/render/raycast_reference.cpp): the face's own normal
// (-step along the crossed axis, facing the camera) under a headlight from
// the camera and a fill light above and to the left of it, plus ambient.
// The headlight makes faces turned towards the viewer brightest, so a
// voxelized sphere darkens towards its rim; the fill light tells the three
// face orientations apart. Faces a voxel's size cannot show a curved
// surface's slope, so a depth cue darkens what lies farther along the view
// axis (depth: 0 at the scene's nearest corner, 1 at its farthest): a
// sphere's rim falls off, a limb in front stands out.

float faceShade(int axis, int step, vec3 headlight, vec3 fill, float ambient, float depth) {
  const float head = max(0.0, -float(step) * headlight[axis]);
  const float side = max(0.0, -float(step) * fill[axis]);
  const float light = min(1.0, ambient + (1.0 - ambient) * (VOX_SHADE_HEADLIGHT * head + VOX_SHADE_FILL * side));
  return light * (1.0 - VOX_SHADE_DEPTH * clamp(depth, 0.0, 1.0));
}
