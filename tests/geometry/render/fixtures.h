#pragma once
// Shared by the ray-casting tests (tests/geometry, tests/gpu) and the
// benchmark: smooth deformations standing in for poses until the
// deformation pipeline produces them, and the golden scenes.

#include "geometry/label_grid.h"
#include "geometry/render/rest_transfer_mesh.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace vox::test {

enum class Deformation {
  Rest,
  Twist,   // about the vertical axis, 0 at the feet to 40 degrees at the head
  Bend,    // the part above 55% of the height leans forward, up to 25 degrees
  Rotate,  // rigid: 30 degrees about the vertical axis
};

inline const char* deformationName(Deformation d) {
  switch (d) {
    case Deformation::Rest: return "rest";
    case Deformation::Twist: return "twist";
    case Deformation::Bend: return "bend";
    case Deformation::Rotate: return "rotate";
  }
  return "?";
}

// Deformed copies of rest positions (grid frame), relative to the grid's box.
inline std::vector<Eigen::Vector3d> deform(const std::vector<Eigen::Vector3d>& rest, const GridGeometry& g, Deformation d) {
  const Eigen::Vector3d lo = g.boxMin(), hi = g.boxMax(), c = 0.5 * (lo + hi);
  const double deg = std::numbers::pi / 180.0;
  std::vector<Eigen::Vector3d> out = rest;
  for (Eigen::Vector3d& p : out) {
    const double h = (p[2] - lo[2]) / (hi[2] - lo[2]);
    switch (d) {
      case Deformation::Rest: break;
      case Deformation::Twist: {
        const Eigen::AngleAxisd r(40.0 * deg * h, Eigen::Vector3d::UnitZ());
        p = c + r * (p - c);
        break;
      }
      case Deformation::Bend: {
        const double pivot = 0.55;
        if (h <= pivot) break;
        const Eigen::Vector3d axisPoint(c[0], c[1], lo[2] + pivot * (hi[2] - lo[2]));
        const Eigen::AngleAxisd r(25.0 * deg * (h - pivot) / (1.0 - pivot), Eigen::Vector3d::UnitX());
        p = axisPoint + r * (p - axisPoint);
        break;
      }
      case Deformation::Rotate: {
        const Eigen::AngleAxisd r(30.0 * deg, Eigen::Vector3d::UnitZ());
        p = c + r * (p - c);
        break;
      }
    }
  }
  return out;
}

// Golden images: the AM phantom through a coarse voxel TM (downsampling 4)
// at rest and in two poses, with and without a cutting plane. PNGs under
// assets/golden/raycast_<name>.png, rendered by the CPU reference.
struct GoldenScene {
  std::string name;
  Deformation deformation;
  std::string camera;
  std::string cut;  // "" = none
};

inline constexpr int kGoldenWidth = 320;
inline constexpr int kGoldenHeight = 240;
inline constexpr int kGoldenTmFactor = 4;

inline std::vector<GoldenScene> goldenScenes() {
  return {
      {"am_rest", Deformation::Rest, "azimuth=20,elevation=10", ""},
      {"am_rest_cut", Deformation::Rest, "azimuth=20,elevation=10", "y<135mm"},
      {"am_twist", Deformation::Twist, "azimuth=20,elevation=10", ""},
      {"am_twist_cut", Deformation::Twist, "azimuth=20,elevation=10", "z>1200mm"},
      {"am_bend", Deformation::Bend, "azimuth=90,elevation=5", ""},
      {"am_bend_cut", Deformation::Bend, "azimuth=90,elevation=5", "x>272mm"},
  };
}

}  // namespace vox::test
