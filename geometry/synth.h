#pragma once
// Synthetic label grids for tests and examples (`voxmorph synth`).

#include "geometry/label_grid.h"
#include "geometry/organ_table.h"

#include <string>

namespace vox {

enum class SynthKind {
  NestedSpheres,   // three concentric materials (1 outer shell, 2, 3 core)
  JunctionSphere,  // a sphere cut into five materials: 1-junction curves and 0-junction points
  StickFigure,     // trunk, head, legs and arms that touch the trunk along its sides
  SkeletonFigure,  // the stick figure's outline with bones named as in the ICRP tables (skeletonFigureBones)
};

// Where synthesize(SkeletonFigure, size) puts its joints, in normalized
// coordinates (the longest axis, z, spans [0, 1]; grid-frame mm = value *
// size * 2): the humeral and femoral head centres and radii, the centres of
// the elbows' and knees' distal bone ends. Right is at low x, anterior at
// low y, superior at high z, as in the ICRP phantoms.
struct SkeletonFigureBones {
  double humeralHeadX[2] = {0.145, 0.455};  // right, left
  double humeralHeadY = 0.15, humeralHeadZ = 0.755, humeralHeadRadius = 0.016;
  double femoralHeadX[2] = {0.2425, 0.3575};
  double femoralHeadY = 0.15, femoralHeadZ = 0.43, femoralHeadRadius = 0.018;
};

// Throws InputError("synth", ...) for an unknown name.
SynthKind synthKindFromName(const std::string& name);
const char* synthKindName(SynthKind kind);

// `size` is the number of voxels along the longest axis (>= 8).
LabelGrid synthesize(SynthKind kind, int size);
// Names and densities of the labels synthesize() writes.
OrganTable synthOrganTable(SynthKind kind);

}  // namespace vox
