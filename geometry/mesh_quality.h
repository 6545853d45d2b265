#pragma once
// Tet quality measures used by `voxmorph info` and the remesher's report.

#include "geometry/tet_mesh.h"

#include <array>
#include <cstdint>
#include <map>

namespace vox {

// The six dihedral angles of tet (a,b,c,d), in degrees, at edges
// (ab, ac, ad, bc, bd, cd).
std::array<double, 6> dihedralAngles(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                     const Eigen::Vector3d& d);

struct TetQualitySummary {
  std::size_t tets = 0;            // tets measured (label > 0)
  double minDihedral = 180.0;      // degrees
  double maxDihedral = 0.0;
  std::size_t under15 = 0;         // tets with a dihedral angle under 15 degrees
  std::size_t under5 = 0;
  double meanDeviationFrom70 = 0;  // mean |angle - 70.53| over all angles
  std::size_t inverted = 0;        // signed volume <= 0
  std::map<std::int32_t, std::size_t> tetsPerLabel;
  std::map<std::int32_t, double> volumePerLabel;  // mm^3
};

// Summary over the domain tets (label > 0).
TetQualitySummary summarizeTetQuality(const TetMesh& mesh);

// Angles of the boundary facets: faces between tets of different labels and
// faces on the domain boundary (domain tets only).
struct BoundaryFacetSummary {
  std::size_t facets = 0;
  double minAngle = 180.0;         // degrees
  double maxAngle = 0.0;
  double meanDeviationFrom60 = 0;  // mean |angle - 60| over all facet angles
};
BoundaryFacetSummary summarizeBoundaryFacets(const TetMesh& mesh);

// Lengths of the edges of the domain tets against a target length l.
struct EdgeLengthSummary {
  std::size_t edges = 0;
  double minLength = 0.0, maxLength = 0.0, meanLength = 0.0;  // mm
  double meanRelativeDeviation = 0.0;  // mean |length - l| / l
};
EdgeLengthSummary summarizeEdgeLengths(const TetMesh& mesh, double target);

}  // namespace vox
