#pragma once
// Per-tet deformation measures of the transfer mesh (TM):
//  - the basis change B_t (thesis ch. 4; D_t in ch. 3): the linear part of
//    the affine map that takes rest tet t onto its deformed copy,
//    B_t = E'_t E_t^-1 with E_t = [v1 - v0, v2 - v0, v3 - v0];
//  - its Laplacian Delta B_t (eq. 4.1), the tet error e_t = ||Delta B_t||_F
//    (eq. 4.5) and the vertex error e_v (eq. 4.6) that drive the
//    deformation-adaptive refinement;
//  - the distortion histograms of Figure 3.19.
//
// Index spaces: tets index TetMesh::tets (#T), vertices index
// TetMesh::positions (#V). Volumes |t| are rest volumes.

#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace vox {

// Inverse of the rest edge matrix E_t of tet t (precomputed by the solvers).
Eigen::Matrix3d restEdgeInverse(const std::vector<Eigen::Vector3d>& rest, const Tet& t);
// B_t = E'_t E_t^-1 for one tet; `restEdgeInv` from restEdgeInverse.
Eigen::Matrix3d basisChange(const Eigen::Matrix3d& restEdgeInv, std::span<const Eigen::Vector3d> deformed, const Tet& t);

// The rotation factor R of the polar decomposition B = R S (S symmetric
// positive semi-definite): the rotation nearest to B in the Frobenius norm.
// Scaled Newton iteration (X <- (g X + X^-T / g) / 2, g = |det X|^-1/3),
// which returns a rotation unchanged (to rounding; the identity exactly);
// svdRotation (below) when det B <= 0 or Newton does not settle.
// Deterministic.
Eigen::Matrix3d polarRotation(const Eigen::Matrix3d& b);
// The rotation nearest to m by its SVD m = U Sigma V^T: U V^T, with the
// column of U of the smallest singular value negated when that would be a
// reflection.
Eigen::Matrix3d svdRotation(const Eigen::Matrix3d& m);

// B_t of every tet: #T matrices. deformed: #V positions. Throws
// InputError("transfer mesh", ...) for a degenerate rest tet.
std::vector<Eigen::Matrix3d> basisChanges(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed);

// |t| of every rest tet (absolute signed volume), #T values.
std::vector<double> tetVolumes(const TetMesh& rest);

// Eq. 4.1: Delta B_t = B_t - sum_{n in T1(t)} |n| B_n / sum_{n in T1(t)} |n|,
// T1(t) the tets sharing a face with t (neighbors from faceNeighbors). A tet
// without face neighbours gets Delta B_t = 0.
std::vector<Eigen::Matrix3d> basisChangeLaplacian(std::span<const Eigen::Matrix3d> basis, std::span<const double> volumes,
                                                  std::span<const std::array<std::int32_t, 4>> neighbors);

// Eq. 4.5: e_t = ||Delta B_t||_F for every tet (#T).
std::vector<double> tetDeformationError(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed);

// Eq. 4.6: e_v = sum_{t in T1(v)} |t| e_t / sum_{t in T1(v)} |t| for every
// vertex (#V); 0 for vertices in no tet.
std::vector<double> vertexDeformationError(const TetMesh& rest, std::span<const double> tetError);

// A volume-weighted histogram over [lo, hi) in equal bins.
struct DistortionHistogram {
  double lo = 0, hi = 0;
  std::vector<double> fractions;  // bins: fraction of the measured volume in each
  double below = 0, above = 0;    // fraction of the volume under lo / at or over hi
  double mean = 0;                // volume-weighted mean of the measure
  double min = 0, max = 0;        // extreme values
  double rmsDeviation = 0;        // volume-weighted RMS distance to the undistorted value
};

// The default bins are centred on the undistorted values (90 degrees, 1).
struct DistortionHistogramOptions {
  int angleBins = 91;        // 1 degree wide over the default range
  double angleMin = 44.5;    // degrees
  double angleMax = 135.5;   // degrees
  int stretchBins = 101;     // 0.01 wide over the default range
  double stretchMin = 0.495;
  double stretchMax = 1.505;
};

struct DistortionHistograms {
  DistortionHistogram angle;    // degrees; undistorted: 90
  DistortionHistogram stretch;  // length ratio; undistorted: 1
  double volume = 0;            // rest volume measured (mm^3)
};

// Figure 3.19's distortion histograms. The thesis measures them on the dual
// of the voxel grid: the edges joining neighbouring voxel centres, which run
// along the grid axes x, y, z. Here they are measured on the TM tets: inside
// tet t every dual edge is mapped by the same B_t (the TM deformation is
// piecewise linear, and the voxels are much smaller than the tets), so each
// tet contributes, weighted by its rest volume,
//  - angle: the three angles between B_t e_x, B_t e_y, B_t e_z (the images of
//    the orthogonal pairs (x,y), (y,z), (z,x));
//  - stretch: |B_t e_x|, |B_t e_y|, |B_t e_z| (the distance ratios of unit
//    dual edges).
// This is the volume-weighted limit of the per-voxel measurement without
// locating every voxel centre in the TM.
DistortionHistograms distortionHistograms(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed,
                                          const DistortionHistogramOptions& options = {});

}  // namespace vox
