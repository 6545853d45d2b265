#pragma once
// The size of a remeshing run before it starts: how many tets an isotropic
// mesh at target length l holds, and the memory the remesher needs for them.
// A length far below the voxel size asks for gigabytes; the mesh and remesh
// commands print this estimate and refuse beyond their memory budget.

#include "geometry/label_grid.h"
#include "geometry/tet_mesh.h"

#include <cstdint>
#include <string>

namespace vox::remesh {

struct MeshingEstimate {
  double domainVolumeMm3 = 0.0;  // labelled volume (label > 0)
  double extentMm = 0.0;         // longest side of the labelled region's box
  std::int64_t tets = 0;         // domain tets of the output
  // Domain tets the remesher starts from: a grid's voxel decomposition, or
  // the input mesh. At a target well above their size the peak is theirs.
  std::int64_t startTets = 0;
  bool fromGrid = false;  // startTets are a grid's voxel decomposition
  std::int64_t bytes = 0;        // peak memory of the remesher
};

// Tets of an isotropic mesh at length l: domain volume over the mean tet
// volume at that length. The factors are the larger of those measured
// (docs/BENCHMARKS.md, "Meshing estimate"): tets per l^3 of domain and peak
// bytes per output tet (the imaginary layer and the complex's tables count).
constexpr double kTetsPerCubicLength = 12.0;
constexpr double kRemeshBytesPerTet = 700.0;
// The decomposition refines to the voxels along every interface, whatever l:
// its tets per voxel face between two labels (label 0 beyond the grid
// included), and the remesher's peak bytes per tet of it.
constexpr double kDecompositionTetsPerInterfaceFace = 7.0;
constexpr double kRemeshBytesPerDecompositionTet = 250.0;

// The peak is the larger of the output's and the starting mesh's.
MeshingEstimate estimateMeshing(const LabelGrid& grid, double targetLength);
// For a mesh, also at least the tets that splitting its edges down to
// e_max = 4/3 l adds (needles have little volume but ask for many splits).
MeshingEstimate estimateMeshing(const TetMesh& mesh, double targetLength);

// "about 346,000 tets and 210 MB"; "about 26093 tets (8.6 M in the voxel
// decomposition) and 2051 MB" when the starting mesh sets the peak.
std::string describeEstimate(const MeshingEstimate& e);

}  // namespace vox::remesh
