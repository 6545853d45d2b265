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
};

// Throws InputError("synth", ...) for an unknown name.
SynthKind synthKindFromName(const std::string& name);
const char* synthKindName(SynthKind kind);

// `size` is the number of voxels along the longest axis (>= 8).
LabelGrid synthesize(SynthKind kind, int size);
// Names and densities of the labels synthesize() writes.
OrganTable synthOrganTable(SynthKind kind);

}  // namespace vox
