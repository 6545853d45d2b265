#pragma once
// Shared by the ray-casting tests (tests/geometry, tests/gpu) and the
// benchmark: smooth deformations standing in for poses, a brute-force
// deformed grid (an independent rasterization of G'), and the golden scenes.

#include "geometry/label_grid.h"
#include "geometry/render/output_grid.h"
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

// The deformed grid G' computed without the ray caster's machinery: every
// tet, in index order, claims the output voxel centres inside it (closed
// barycentric test) that no lower tet claimed, and gives them the label of
// the source voxel its barycentric map sends them to.
inline LabelGrid bruteForceDeformedGrid(const LabelGrid& source, const TetMesh& rest, const std::vector<Eigen::Vector3d>& deformed) {
  const GridGeometry& sg = source.geometry();
  LabelGrid out(outputGridGeometry(sg, deformed), 0);
  const GridGeometry& og = out.geometry();
  std::vector<std::uint8_t> claimed(std::size_t(og.voxelCount()), 0);
  for (const Tet& t : rest.tets) {
    Eigen::Matrix3d m;
    for (int k = 0; k < 3; ++k) m.col(k) = deformed[t[k + 1]] - deformed[t[0]];
    const Eigen::Matrix3d inv = m.inverse();
    Eigen::Vector3d lo = deformed[t[0]], hi = deformed[t[0]];
    for (int k = 1; k < 4; ++k) {
      lo = lo.cwiseMin(deformed[t[k]]);
      hi = hi.cwiseMax(deformed[t[k]]);
    }
    Index3 a, b;
    for (int k = 0; k < 3; ++k) {
      a[k] = std::max<std::int64_t>(0, std::int64_t(std::ceil((lo[k] - og.origin[k]) / og.spacing[k])));
      b[k] = std::min<std::int64_t>(og.dims[k] - 1, std::int64_t(std::floor((hi[k] - og.origin[k]) / og.spacing[k])));
    }
    for (std::int64_t k = a[2]; k <= b[2]; ++k)
      for (std::int64_t j = a[1]; j <= b[1]; ++j)
        for (std::int64_t i = a[0]; i <= b[0]; ++i) {
          const std::int64_t idx = og.index(i, j, k);
          if (claimed[std::size_t(idx)]) continue;
          const Eigen::Vector3d l = inv * (og.voxelCenter(i, j, k) - deformed[t[0]]);
          const double l0 = 1.0 - l.sum();
          if (l.minCoeff() < -1e-9 || l0 < -1e-9) continue;
          claimed[std::size_t(idx)] = 1;
          Eigen::Vector3d s = rest.positions[t[0]];
          for (int q = 0; q < 3; ++q) s += l[q] * (rest.positions[t[q + 1]] - rest.positions[t[0]]);
          const Eigen::Vector3d ci = sg.continuousIndex(s);
          out.labels()[std::size_t(idx)] =
              source.atOr(std::int64_t(std::floor(ci[0] + 0.5)), std::int64_t(std::floor(ci[1] + 0.5)), std::int64_t(std::floor(ci[2] + 0.5)));
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
