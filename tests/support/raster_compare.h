#pragma once
// Comparison of a GPU rasterization with its CPU reference: every voxel
// where they differ must be a float/double tie (a voxel centre within 1e-6
// barycentric of a tet face, or a source position within float rounding of
// a source voxel boundary), and at most 1e-5 of the voxels may differ.

#include "geometry/raster/rasterize.h"
#include "geometry/label_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>

namespace vox::test {

// Largest barycentric margin (|lambda| of a face, dimensionless) at which the
// float evaluation may decide a containment test differently from double.
constexpr double kFaceTie = 1e-6;
// Largest distance (source voxels) from a source voxel boundary at which the
// float source position may round differently from double.
constexpr double kSourceTie = 1e-4;

struct Disagreement {
  std::int64_t voxels = 0;       // differing output voxels
  std::int64_t faceTies = 0;     // explained by a near-face containment test
  std::int64_t sourceTies = 0;   // explained by a source position near a voxel boundary
  std::int64_t unexplained = 0;
  double maxFaceMargin = 0.0;    // over face ties
  double maxSourceMargin = 0.0;  // over source ties
};

// Smallest |min_k lambda_k| over the tets t <= the double winner whose box
// holds q: a differing winner needs a containment test that float and double
// decide differently, and only those tets can have one.
inline double faceMargin(const RasterizationPlan& plan, std::int32_t x, std::int32_t y, std::int32_t z, std::int32_t& winner) {
  winner = -1;
  double margin = 1e300;
  for (std::size_t t = 0; t < plan.tets().size(); ++t) {
    const LatticeTet& lt = plan.tets()[t];
    if (lt.empty() || x < lt.lo[0] || x > lt.hi[0] || y < lt.lo[1] || y > lt.hi[1] || z < lt.lo[2] || z > lt.hi[2]) continue;
    margin = std::min(margin, std::abs(lt.barycentric(x, y, z).minCoeff()));
    if (lt.contains(x, y, z)) {
      winner = std::int32_t(t);
      break;
    }
  }
  return margin;
}

// Distance of the double source position of lattice point q (through tet t)
// to the nearest source voxel boundary, in voxels.
inline double sourceMargin(const RasterizationPlan& plan, std::int32_t t, std::int32_t x, std::int32_t y, std::int32_t z) {
  const Eigen::Vector4d l = plan.tets()[std::size_t(t)].barycentric(x, y, z);
  const auto c = plan.restCorners(t);
  const Eigen::Vector3d p = l[0] * c[0] + l[1] * c[1] + l[2] * c[2] + l[3] * c[3];
  double m = 1e300;
  for (int a = 0; a < 3; ++a) m = std::min(m, std::abs(p[a] - std::floor(p[a]) - 0.5));
  return m;
}

inline Disagreement compare(const RasterizationPlan& plan, const LabelGrid& cpu, const LabelGrid& gpu) {
  Disagreement d;
  EXPECT_EQ(cpu.dims(), gpu.dims());
  if (cpu.dims() != gpu.dims()) return d;
  const int k = plan.samples();
  for (std::int64_t v = 0; v < cpu.voxelCount(); ++v) {
    if (cpu.labels()[std::size_t(v)] == gpu.labels()[std::size_t(v)]) continue;
    ++d.voxels;
    // The voxel's label is decided by its k^3 samples: one of them must be a tie.
    const Index3 o = cpu.geometry().ijk(v);
    double face = 1e300, source = 1e300;
    for (int c = 0; c < k; ++c)
      for (int b = 0; b < k; ++b)
        for (int a = 0; a < k; ++a) {
          const std::int32_t x = std::int32_t(o[0] * k + a), y = std::int32_t(o[1] * k + b), z = std::int32_t(o[2] * k + c);
          std::int32_t winner;
          face = std::min(face, faceMargin(plan, x, y, z, winner));
          if (winner >= 0) source = std::min(source, sourceMargin(plan, winner, x, y, z));
        }
    if (face <= kFaceTie) {
      ++d.faceTies;
      d.maxFaceMargin = std::max(d.maxFaceMargin, face);
    } else if (source <= kSourceTie) {
      ++d.sourceTies;
      d.maxSourceMargin = std::max(d.maxSourceMargin, source);
    } else {
      ++d.unexplained;
      ADD_FAILURE() << "voxel " << o[0] << "," << o[1] << "," << o[2] << ": cpu " << cpu.labels()[std::size_t(v)] << " gpu "
                    << gpu.labels()[std::size_t(v)] << ", face margin " << face << ", source margin " << source;
    }
  }
  return d;
}

inline void expectEquivalent(const std::string& what, const RasterizationPlan& plan, const LabelGrid& cpu, const LabelGrid& gpu) {
  const Disagreement d = compare(plan, cpu, gpu);
  const double fraction = double(d.voxels) / double(cpu.voxelCount());
  std::cout << "[ stats    ] " << what << ": " << cpu.voxelCount() << " voxels, " << d.voxels << " differ (" << fraction * 100.0
            << "%): " << d.faceTies << " face ties (max margin " << d.maxFaceMargin << "), " << d.sourceTies
            << " source ties (max " << d.maxSourceMargin << " voxel)\n";
  EXPECT_EQ(d.unexplained, 0) << what;
  EXPECT_LE(fraction, 1e-5) << what;
}

}  // namespace vox::test
