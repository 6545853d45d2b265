// Smooth shading (geometry/render/surface_normals.h): normals of a sliced
// sphere follow the sphere at rest and through a rotated transfer mesh, with
// its outer shell hidden too; cut faces are flat; face shading keeps the
// voxel faces; and the thin dark lines of face shading across the slices'
// steps are gone (the measure of tests/bench/dark_lines.py).

#include "geometry/error.h"
#include "geometry/render/raycast_reference.h"
#include "geometry/render/raycast_scene.h"
#include "geometry/render/rest_transfer_mesh.h"
#include "geometry/render/surface_normals.h"
#include "tests/geometry/render/fixtures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <numeric>

namespace vox {
namespace {

// A sphere of radius 70 mm (label 1) around a core of radius 40 mm (label 2)
// on 2 x 2 x 8 mm voxels, the ICRP phantoms' anisotropy exaggerated.
LabelGrid slicedSphere() {
  GridGeometry g;
  g.dims = {80, 80, 24};
  g.spacing = {2.0, 2.0, 8.0};
  LabelGrid grid(g, 0);
  const Eigen::Vector3d c = 0.5 * (g.boxMin() + g.boxMax());
  for (std::int64_t k = 0; k < g.dims[2]; ++k)
    for (std::int64_t j = 0; j < g.dims[1]; ++j)
      for (std::int64_t i = 0; i < g.dims[0]; ++i) {
        const double r = (g.origin + g.spacing.cwiseProduct(Eigen::Vector3d(double(i), double(j), double(k))) - c).norm();
        grid.at(i, j, k) = r <= 40.0 ? 2 : (r <= 70.0 ? 1 : 0);
      }
  return grid;
}

Eigen::Vector3d sphereCentre(const LabelGrid& grid) { return 0.5 * (grid.geometry().boxMin() + grid.geometry().boxMax()); }

struct Scene {
  RaycastMesh mesh;
  RaycastFrame frame;
  RaycastView view;
  std::vector<TetFactors> factors;
};

Scene makeScene(const LabelGrid& grid, const TetMesh& rest, const std::vector<Eigen::Vector3d>& posed, const std::string& camera,
                const CuttingPlanes& cuts, int w, int h) {
  Scene s;
  s.mesh = buildRaycastMesh(rest, grid.geometry());
  s.frame = prepareRaycastFrame(s.mesh, posed);
  s.view = makeRaycastView(s.frame, parseCamera(camera, s.frame.toGrid(s.frame.cellsLo), s.frame.toGrid(s.frame.cellsHi), w, h), cuts);
  s.factors = computeTetFactors(s.mesh, s.frame);
  return s;
}

// The share of the non-background pixels darker (luma) than `ratio` times
// the median of their 5x5 neighbourhood (edge pixels replicated), as
// tests/bench/dark_lines.py measures it.
double darkLineFraction(const RgbImage& image, Rgb background, double ratio = 0.6) {
  const int w = image.width, h = image.height;
  auto luma = [&](int x, int y) {
    const Rgb c = image.at(std::clamp(x, 0, w - 1), std::clamp(y, 0, h - 1));
    return 0.299 * c.r + 0.587 * c.g + 0.114 * c.b;
  };
  std::size_t body = 0, dark = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (image.at(x, y) == background) continue;
      ++body;
      double window[25];
      for (int k = 0; k < 25; ++k) window[k] = luma(x + k % 5 - 2, y + k / 5 - 2);
      std::nth_element(window, window + 12, window + 25);
      dark += luma(x, y) < ratio * window[12];
    }
  return body ? double(dark) / double(body) : 0.0;
}

double degrees(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

TEST(SmoothShading, NormalsFollowTheSphereAtRestRotatedAndStretchedAndWithTheShellHidden) {
  const LabelGrid grid = slicedSphere();
  const Eigen::Vector3d centre = sphereCentre(grid);
  const TetMesh box = boxTransferMesh(grid);
  const TetMesh coarse = coarseVoxelTransferMesh(grid, 2);
  // Stretched 1.5 times along x, the sphere becomes an ellipsoid whose
  // normal at q is (q - c) ./ (1.5^2, 1, 1): the gradient goes through the
  // inverse transpose of the stretch, not the stretch itself.
  const Eigen::Vector3d stretch(1.5, 1.0, 1.0);
  std::vector<Eigen::Vector3d> stretched = coarse.positions;
  for (Eigen::Vector3d& p : stretched) p = centre + stretch.cwiseProduct(p - centre);
  struct Case {
    const char* name;
    const TetMesh& rest;
    std::vector<Eigen::Vector3d> posed;
    Eigen::Vector3d axes;  // the ellipsoid's semi-axes over the sphere's radius
  };
  const Case cases[] = {{"rest", box, box.positions, Eigen::Vector3d::Ones()},
                        {"rotated", coarse, test::deform(coarse.positions, grid.geometry(), test::Deformation::Rotate),
                         Eigen::Vector3d::Ones()},
                        {"stretched", coarse, stretched, stretch}};
  for (const Case& c : cases)
    for (const char* hide : {"", "1"}) {
      Palette palette(grid.maxLabel());
      if (*hide) palette.hide(hide);
      const Scene s = makeScene(grid, c.rest, c.posed, "azimuth=20,elevation=25", {}, 160, 120);
      std::vector<double> smoothAngles;
      double facesSum = 0.0;
      std::size_t hits = 0;
      for (int y = 0; y < 120; ++y)
        for (int x = 0; x < 160; ++x) {
          const Eigen::Vector3d d = s.view.direction(x, y);
          const RayResult r = traceRayReference(grid, s.mesh, s.frame, s.factors, s.view, palette, s.view.eye, d, {});
          if (!r.hit) continue;
          ++hits;
          const Eigen::Vector3d smooth = surfaceNormal(r, grid, s.mesh, s.frame, s.factors, s.view, palette, SurfaceNormals::Smooth);
          const Eigen::Vector3d faces = surfaceNormal(r, grid, s.mesh, s.frame, s.factors, s.view, palette, SurfaceNormals::Faces);
          const Eigen::Vector3d toCamera = -d.cwiseProduct(s.frame.output.spacing);
          EXPECT_NEAR(smooth.norm(), 1.0, 1e-9);
          EXPECT_GT(smooth.dot(toCamera), 0.0);
          EXPECT_EQ(faces.cwiseAbs().sum(), 1.0);
          EXPECT_EQ(faces[r.axis], -double(r.step));
          const Eigen::Vector3d radial = (s.frame.toGrid(r.point) - centre).cwiseQuotient(c.axes.cwiseProduct(c.axes));
          smoothAngles.push_back(degrees(smooth, radial));
          facesSum += degrees(faces, radial);
        }
      ASSERT_GT(hits, 1000u) << c.name << " hide '" << hide << "'";
      // At the silhouette the normal is turned towards the camera, away from
      // the radius: the 95th percentile, not the worst, is bounded.
      const double smoothMean = std::accumulate(smoothAngles.begin(), smoothAngles.end(), 0.0) / double(hits);
      const double facesMean = facesSum / double(hits);
      std::nth_element(smoothAngles.begin(), smoothAngles.begin() + std::ptrdiff_t(0.95 * double(hits)), smoothAngles.end());
      const double smooth95 = smoothAngles[std::size_t(0.95 * double(hits))];
      std::printf("%s, hide '%s': angle to the expected normal, mean %.1f degrees smooth, %.1f faces; 95th percentile smooth %.1f\n", c.name,
                  hide, smoothMean, facesMean, smooth95);
      EXPECT_LT(smoothMean, 12.0) << c.name << " hide '" << hide << "'";
      EXPECT_LT(smooth95, 25.0) << c.name << " hide '" << hide << "'";
      EXPECT_GT(facesMean, 3.0 * smoothMean) << c.name << " hide '" << hide << "'";
    }
}

TEST(SmoothShading, CutFacesAreFlat) {
  const LabelGrid grid = slicedSphere();
  const Eigen::Vector3d n = Eigen::Vector3d(1.0, -0.4, 0.3).normalized();
  CuttingPlanes cuts;
  cuts.add("plane=" + std::to_string(n[0]) + "," + std::to_string(n[1]) + "," + std::to_string(n[2]) + "," +
           std::to_string(n.dot(sphereCentre(grid))));
  const TetMesh coarse = coarseVoxelTransferMesh(grid, 2);
  const Palette palette(grid.maxLabel());
  const Scene s = makeScene(grid, coarse, test::deform(coarse.positions, grid.geometry(), test::Deformation::Rotate),
                            "azimuth=60,elevation=10", cuts, 160, 120);
  std::size_t onCut = 0;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x) {
      const RayResult r = traceRayReference(grid, s.mesh, s.frame, s.factors, s.view, palette, s.view.eye, s.view.direction(x, y), {});
      if (!r.hit) continue;
      Eigen::Vector3d before(double(r.cell[0]), double(r.cell[1]), double(r.cell[2]));
      before[r.axis] -= double(r.step);
      if (!cuts.removes(s.frame.toGrid(before))) continue;
      ++onCut;
      const Eigen::Vector3d normal = surfaceNormal(r, grid, s.mesh, s.frame, s.factors, s.view, palette, SurfaceNormals::Smooth);
      // The plane went through its text form, six digits.
      EXPECT_LT((normal - n).norm(), 1e-5) << "pixel " << x << "," << y;
    }
  EXPECT_GT(onCut, 1000u);
}

TEST(SmoothShading, LeavesNoDarkLinesAcrossTheSlicesSteps) {
  // Seen from the front and a little below, face shading draws a dark line
  // wherever the slices step by a voxel (their downward faces nearly edge-on
  // under the headlight, away from the fill light); smooth shading leaves under 0.2% of the sphere's pixels
  // darker than 60% of their 5x5 median.
  const LabelGrid grid = slicedSphere();
  const TetMesh box = boxTransferMesh(grid);
  const Palette palette(grid.maxLabel());
  const Scene s = makeScene(grid, box, box.positions, "azimuth=0,elevation=-10", {}, 320, 320);
  RaycastShading shading;
  const RgbImage smooth = raycastReference(grid, s.mesh, s.frame, s.view, palette, shading);
  shading.normals = SurfaceNormals::Faces;
  const RgbImage faces = raycastReference(grid, s.mesh, s.frame, s.view, palette, shading);
  const double smoothDark = darkLineFraction(smooth, shading.background), facesDark = darkLineFraction(faces, shading.background);
  std::printf("dark-line fraction: faces %.3f%%, smooth %.3f%%\n", 100.0 * facesDark, 100.0 * smoothDark);
  EXPECT_GT(facesDark, 0.01);
  EXPECT_LT(smoothDark, 0.002);
}

TEST(SmoothShading, NamesParse) {
  EXPECT_EQ(parseSurfaceNormals("smooth"), SurfaceNormals::Smooth);
  EXPECT_EQ(parseSurfaceNormals("faces"), SurfaceNormals::Faces);
  EXPECT_STREQ(surfaceNormalsName(SurfaceNormals::Faces), "faces");
  EXPECT_THROW(parseSurfaceNormals("flat"), InputError);
  EXPECT_EQ(RaycastShading{}.normals, SurfaceNormals::Smooth);
}

}  // namespace
}  // namespace vox
