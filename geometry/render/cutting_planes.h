#pragma once
// Cutting planes (thesis 5.2.3): up to three axis-aligned planes and one free
// plane. A voxel of the rendered grid whose centre lies on the averted side of
// any plane is treated as background, so the ray continues behind it.

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace vox {

// The averted (removed) side of a plane: centres c with normal . c > offset
// (grid frame, mm).
struct CuttingPlane {
  Eigen::Vector3d normal{1, 0, 0};
  double offset = 0.0;

  bool removes(const Eigen::Vector3d& centre) const { return normal.dot(centre) > offset; }
};

struct CuttingPlanes {
  std::optional<CuttingPlane> axis[3];  // normal +-x, +-y, +-z
  std::optional<CuttingPlane> free;

  // The active planes, axis planes first (at most four).
  std::vector<CuttingPlane> active() const;
  bool removes(const Eigen::Vector3d& centre) const;

  // Adds one plane from its command-line form:
  //   "x>120mm", "y<-40", "z>1500mm"  removes the voxels whose centre
  //                                   coordinate is above (>) or below (<)
  //                                   the value (mm; the suffix is optional)
  //   "plane=nx,ny,nz,d"              removes the centres c with n . c > d
  //                                   (n need not be unit; d in mm times |n|)
  // Throws InputError("--cut", ...) for malformed text, a zero normal, or a
  // second plane on the same axis or a second free plane.
  void add(const std::string& text);
};

}  // namespace vox
