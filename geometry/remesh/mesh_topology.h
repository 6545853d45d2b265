#pragma once
// Topology of the labels of a tet mesh or a label grid, to check that
// (re)meshing kept it: per label, the connected components of its tets
// (through shared faces) and the Euler characteristic V - E + F - T of its
// closed region; per label set, the connected components of its 1-junctions
// (edges whose incident tets carry three or more labels, the outside
// counting as label 0) and the number of its 0-junctions (vertices that
// classifyVertex calls corners).

#include "geometry/label_grid.h"
#include "geometry/tet_mesh.h"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace vox::remesh {

struct LabelTopology {
  std::size_t tets = 0;        // tets (or voxels)
  std::size_t components = 0;  // face-connected components
  std::int64_t euler = 0;      // Euler characteristic of the closed region
  bool operator==(const LabelTopology&) const = default;
};

struct MeshTopology {
  std::map<std::int32_t, LabelTopology> labels;                       // domain labels (> 0)
  std::map<std::vector<std::int32_t>, std::size_t> junctionCurves;    // 1-junction components per label set
  std::map<std::vector<std::int32_t>, std::size_t> junctionPoints;    // 0-junctions per label set
  std::size_t featureEdges = 0;                                       // edges on 1-junctions
};

// Topology of the domain tets (label > 0) of `mesh`; other tets are outside.
MeshTopology computeMeshTopology(const TetMesh& mesh);
// Topology of the closed voxel regions of `grid` (label 0 is outside), equal
// to computeMeshTopology of its six-tet decomposition but computed on the
// cubical complex, without building tets.
MeshTopology computeGridTopology(const LabelGrid& grid);

// What differs between `expected` and `actual`, one line per difference,
// ignoring tet counts and the number of feature edges; empty when the
// topology is the same.
std::vector<std::string> compareTopology(const MeshTopology& expected, const MeshTopology& actual);

}  // namespace vox::remesh
