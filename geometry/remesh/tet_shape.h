#pragma once
// Shape measures of single tets used to accept or reject an operation.

#include <Eigen/Core>

namespace vox::remesh {

// Volume-length quality 6 sqrt(2) V / l_rms^3: 1 for the regular tet, near 0
// for slivers, needles and caps, negative when inverted. Cheap (no roots but
// one) and scale invariant.
double volumeLengthQuality(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                           const Eigen::Vector3d& d);

// Cosine of the smallest interior dihedral angle of (a, b, c, d). Comparing
// cosines orders tets by their worst angle without calling acos; a flat tet
// gives 1.
double minDihedralCosine(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                         const Eigen::Vector3d& d);

// Smallest interior dihedral angle in degrees.
double minDihedralDegrees(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                          const Eigen::Vector3d& d);

// An operation may not create a tet whose volume-length quality falls below
// this floor, unless the tet it replaces was already worse: positive volume
// alone lets numerically flat tets through.
inline constexpr double kQualityFloor = 1e-3;

}  // namespace vox::remesh
