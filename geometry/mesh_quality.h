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

}  // namespace vox
