#pragma once
// How far the remeshed interfaces moved: a sampled Hausdorff distance
// between the boundary surface of each label's region in two meshes (faces
// of the label's tets whose other side is another label or the outside).

#include "geometry/tet_mesh.h"

#include <cstddef>
#include <cstdint>
#include <map>

namespace vox::remesh {

struct InterfaceDistance {
  double outputToInput = 0.0;  // largest distance from an output sample to the input surface (mm)
  double inputToOutput = 0.0;  // and back
  double hausdorff() const { return outputToInput > inputToOutput ? outputToInput : inputToOutput; }
};

// For every label present in both meshes, both one-sided distances. Samples
// are the vertices, edge mid-points and centroids of the boundary facets, at
// most `maxSamples` facets per label and side (evenly strided, so the value
// is a lower bound of the true Hausdorff distance); distances to the other
// surface are exact point-triangle distances (CGAL AABB tree).
std::map<std::int32_t, InterfaceDistance> interfaceDistances(const TetMesh& input, const TetMesh& output,
                                                             std::size_t maxSamples = 100000, int threads = 2);

}  // namespace vox::remesh
