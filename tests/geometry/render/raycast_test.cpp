// CPU reference of the transfer-mesh-guided ray caster: its building blocks
// against brute force, rest renderings through different TMs against each
// other, posed renderings against the rasterized grid G', cutting planes,
// hidden labels, bad input and the golden images.

#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/png_io.h"
#include "geometry/organ_table.h"
#include "geometry/render/boundary_bvh.h"
#include "geometry/skeleton/label_groups.h"
#include "geometry/raster/rasterize.h"
#include "geometry/deform/transfer_mesh.h"
#include "geometry/render/raycast_reference.h"
#include "geometry/render/raycast_scene.h"
#include "geometry/render/rest_transfer_mesh.h"
#include "geometry/synth.h"
#include "tests/geometry/render/fixtures.h"
#include "tests/support/test_environment.h"

#include <Eigen/LU>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <random>

namespace vox {
namespace {

// The stick figure with the phantoms' anisotropy (slices thicker than rows).
LabelGrid stickFigure() {
  LabelGrid g = synthesize(SynthKind::StickFigure, 64);
  g.geometry().spacing = {1.5, 1.5, 4.0};
  g.geometry().origin = {-20.0, 35.0, 100.0};
  return g;
}

// Stated bound of the difference between rendering a pose and rendering,
// through an identity TM, the grid the rasterizer produces for it: at most
// 0.2% of the pixels, each a voxel the TM rendering missed (grazing rays).
constexpr double kRasterizedBound = 0.002;

const LabelGrid& amPhantom() {
  static const LabelGrid grid = readGrid(test::assetPath("icrp110_am.nii.gz"));
  return grid;
}

struct Rendered {
  RgbImage image;
  RaycastFrame frame;
  RaycastView view;
  RaycastStats stats;
};

Rendered renderReference(const LabelGrid& grid, const RaycastMesh& mesh, const std::vector<Eigen::Vector3d>& positions,
                         const Camera& camera, const CuttingPlanes& cuts, const Palette& palette, const RaycastShading& shading = {}) {
  Rendered r;
  r.frame = prepareRaycastFrame(mesh, positions);
  r.view = makeRaycastView(r.frame, camera, cuts);
  r.image = raycastReference(grid, mesh, r.frame, r.view, palette, shading, {}, &r.stats);
  return r;
}

Camera sceneCamera(const RaycastFrame& frame, const std::string& spec, int w, int h) {
  return parseCamera(spec, frame.toGrid(frame.cellsLo), frame.toGrid(frame.cellsHi), w, h);
}

// Brute-force point location in the deformed TM: strictly inside some tet.
class TetLocator {
public:
  TetLocator(const TetMesh& rest, const std::vector<Eigen::Vector3d>& p) {
    for (const Tet& t : rest.tets) {
      Eigen::Matrix3d m;
      for (int k = 0; k < 3; ++k) m.col(k) = p[t[k + 1]] - p[t[0]];
      inverse_.push_back(m.inverse());
      origin_.push_back(p[t[0]]);
      Eigen::Vector3d lo = p[t[0]], hi = p[t[0]];
      for (int k = 1; k < 4; ++k) {
        lo = lo.cwiseMin(p[t[k]]);
        hi = hi.cwiseMax(p[t[k]]);
      }
      lo_.push_back(lo);
      hi_.push_back(hi);
    }
  }
  bool strictlyInside(const Eigen::Vector3d& x) const {
    for (std::size_t t = 0; t < inverse_.size(); ++t) {
      if ((x.array() < lo_[t].array()).any() || (x.array() > hi_[t].array()).any()) continue;
      const Eigen::Vector3d l = inverse_[t] * (x - origin_[t]);
      if (l.minCoeff() > 1e-7 && 1.0 - l.sum() > 1e-7) return true;
    }
    return false;
  }

private:
  std::vector<Eigen::Matrix3d> inverse_;
  std::vector<Eigen::Vector3d> origin_, lo_, hi_;
};

// Renders `grid` through `rest` deformed by `d`, and the grid G' that the
// rasterizer produces for that pose through an identity box TM, with the
// same camera and cuts, lit with face normals (smooth normals of G' and of
// the rest grid mapped through the TM differ by the resampling; the question
// here is which voxel each ray shows). Returns the number of differing pixels, after checking that each is a
// voxel the TM rendering missed, never one it invented: G' shows a voxel
// there, and the TM rendering shows nothing or a voxel of G' farther along
// the ray. Prints how many of the missed voxels the ray crosses only outside
// the TM (it grazes the surface); the others have centres the walk cannot
// reach through face neighbours (concavities, tets that touch along an edge).
std::size_t poseVersusRasterizedGrid(const LabelGrid& grid, const TetMesh& rest, test::Deformation d, const std::string& cameraSpec,
                                     const std::string& cut, int w, int h) {
  const Palette palette(grid.maxLabel());
  CuttingPlanes cuts;
  if (!cut.empty()) cuts.add(cut);
  const RaycastMesh mesh = buildRaycastMesh(rest, grid.geometry());
  const std::vector<Eigen::Vector3d> posed = test::deform(rest.positions, grid.geometry(), d);
  RaycastFrame frame = prepareRaycastFrame(mesh, posed);
  const Camera camera = sceneCamera(frame, cameraSpec, w, h);
  RaycastShading faces;
  faces.normals = SurfaceNormals::Faces;
  const Rendered tm = renderReference(grid, mesh, posed, camera, cuts, palette, faces);

  const LabelGrid rasterized = rasterizeDeformedGrid(grid, rest, posed);
  EXPECT_EQ(rasterized.geometry().dims, tm.frame.output.dims);
  EXPECT_TRUE(rasterized.geometry().origin.isApprox(tm.frame.output.origin));
  const TetMesh box = boxTransferMesh(rasterized);
  const RaycastMesh boxMesh = buildRaycastMesh(box, rasterized.geometry());
  const Rendered identity = renderReference(rasterized, boxMesh, box.positions, camera, cuts, palette, faces);

  const ImageDifference diff = compareImages(tm.image, identity.image, 0);
  if (diff.differing == 0) return 0;
  const TetLocator locator(rest, posed);
  const auto factors = computeTetFactors(mesh, tm.frame);
  const auto boxFactors = computeTetFactors(boxMesh, identity.frame);
  const Eigen::Vector3d half = 0.5 * grid.geometry().spacing;
  std::size_t grazing = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (tm.image.at(x, y) == identity.image.at(x, y)) continue;
      const RayResult a = traceRayReference(grid, mesh, tm.frame, factors, tm.view, palette, tm.view.eye, tm.view.direction(x, y), {});
      const RayResult b = traceRayReference(rasterized, boxMesh, identity.frame, boxFactors, identity.view, palette, identity.view.eye,
                                            identity.view.direction(x, y), {});
      const std::string where = "pixel " + std::to_string(x) + "," + std::to_string(y) + " (" + test::deformationName(d) + ", cut '" + cut + "')";
      EXPECT_TRUE(b.hit) << where << ": the TM rendering shows a voxel the rasterized grid does not";
      if (!b.hit) continue;
      const Eigen::Vector3d eye = identity.view.camera.eye, dir = identity.view.camera.direction(x, y);
      auto segment = [&](const Eigen::Vector3d& centre, double& t0, double& t1) {
        t0 = 0.0;
        t1 = 1e300;
        for (int k = 0; k < 3; ++k) {
          double u = (centre[k] - half[k] - eye[k]) / dir[k], v = (centre[k] + half[k] - eye[k]) / dir[k];
          if (u > v) std::swap(u, v);
          t0 = std::max(t0, u);
          t1 = std::min(t1, v);
        }
      };
      const Eigen::Vector3d cb = identity.frame.toGrid(Eigen::Vector3d(double(b.cell[0]), double(b.cell[1]), double(b.cell[2])));
      double b0, b1;
      segment(cb, b0, b1);
      if (a.hit) {
        const Eigen::Vector3d ca = tm.frame.toGrid(Eigen::Vector3d(double(a.cell[0]), double(a.cell[1]), double(a.cell[2])));
        double a0, a1;
        segment(ca, a0, a1);
        EXPECT_GT(a0, b0 - 1e-9) << where << ": the TM rendering shows a voxel in front of the rasterized grid's";
        Index3 i;
        EXPECT_TRUE(rasterized.geometry().voxelAt(ca, i));
        EXPECT_EQ(a.label, rasterized.atOr(i[0], i[1], i[2])) << where << ": the voxel shown has another label in the rasterized grid";
      }
      bool crossedInside = false;
      for (int s = 1; s < 32 && !crossedInside; ++s) crossedInside = locator.strictlyInside(eye + (b0 + (b1 - b0) * s / 32.0) * dir);
      grazing += !crossedInside;
    }
  std::printf("%s, cut '%s': %zu pixels differ from the rasterized grid's rendering, %zu where the ray grazes the TM\n",
              test::deformationName(d), cut.c_str(), diff.differing, grazing);
  return diff.differing;
}

TEST(RenderFrame, TraversesTheRasterizersGridInAShiftedIndexFrame) {
  const LabelGrid grid = stickFigure();
  const TetMesh tm = coarseVoxelTransferMesh(grid, 3);
  const RaycastMesh mesh = buildRaycastMesh(tm, grid.geometry());
  const std::vector<Eigen::Vector3d> posed = test::deform(tm.positions, grid.geometry(), test::Deformation::Twist);
  const RaycastFrame frame = prepareRaycastFrame(mesh, posed);
  const GridGeometry g = deformedGridGeometry(grid.geometry(), posed);
  EXPECT_EQ(frame.output.dims, g.dims);
  EXPECT_TRUE(frame.output.origin.isApprox(g.origin));
  // Render cell c is output voxel c + cellShift; the cells' box is G''s.
  const Eigen::Vector3d corner(2, 5, 7);
  const Eigen::Vector3d shift(double(frame.cellShift[0]), double(frame.cellShift[1]), double(frame.cellShift[2]));
  EXPECT_TRUE(frame.toGrid(corner - shift).isApprox(g.voxelCenter(2, 5, 7)));
  EXPECT_TRUE(frame.toRender(g.voxelCenter(2, 5, 7)).isApprox(corner - shift));
  EXPECT_TRUE(frame.toGrid(frame.cellsLo).isApprox(g.boxMin()));
  EXPECT_TRUE(frame.toGrid(frame.cellsHi).isApprox(g.boxMax()));
  for (std::size_t v = 0; v < posed.size(); ++v) EXPECT_TRUE(frame.toGrid(frame.positions[v]).isApprox(posed[v]));
}

TEST(RenderTetFactors, ReproduceBarycentricCoordinates) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  for (int n = 0; n < 100; ++n) {
    const Eigen::Vector3d v[4] = {{u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}};
    const TetFactors f = tetFactors(v[0], v[1], v[2], v[3]);
    const Eigen::Vector4d w(0.1, 0.2, 0.3, 0.4);
    const Eigen::Vector3d p = w[0] * v[0] + w[1] * v[1] + w[2] * v[2] + w[3] * v[3];
    for (int k = 1; k < 4; ++k) EXPECT_NEAR(f.planes[k - 1].head<3>().dot(p - f.anchor) + f.planes[k - 1][3], w[k], 1e-9);
  }
  // A flat tet contains no point: lambda_1..3 = -1 everywhere.
  const TetFactors flat = tetFactors({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0});
  for (const auto& plane : flat.planes) EXPECT_EQ(plane, Eigen::Vector4d(0, 0, 0, -1));
}

TEST(RenderBoundaryBvh, FirstEntryMatchesBruteForce) {
  const LabelGrid grid = stickFigure();
  const TetMesh rest = coarseVoxelTransferMesh(grid, 2);
  const RaycastMesh mesh = buildRaycastMesh(rest, grid.geometry());
  const RaycastFrame frame = prepareRaycastFrame(mesh, test::deform(rest.positions, grid.geometry(), test::Deformation::Twist));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Vector3d centre = 0.5 * (frame.cellsLo + frame.cellsHi);
  const double radius = (frame.cellsHi - frame.cellsLo).norm();
  int hits = 0;
  for (int n = 0; n < 400; ++n) {
    const Eigen::Vector3d o = centre + radius * Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    const Eigen::Vector3d target = centre + 0.3 * radius * Eigen::Vector3d(u(rng), u(rng), u(rng));
    const Eigen::Vector3d d = target - o;
    FaceHit after{0.0, -1};
    for (int entry = 0; entry < 6; ++entry) {
      const FaceHit h = firstEntryAfter(frame.bvh, mesh.boundary, frame.positions, o, d, after.t, after.face);
      // Brute force over every face, with a one-face BVH.
      FaceHit best{1e300, -1};
      for (std::size_t f = 0; f < mesh.boundary.size(); ++f) {
        std::vector<BoundaryFace> one = {mesh.boundary[f]};
        std::vector<BvhNode> node = buildBoundaryBvh(one, frame.positions);
        const FaceHit g = firstEntryAfter(node, one, frame.positions, o, d, after.t, after.face == std::int32_t(f) ? 0 : -1);
        const bool later = g.valid() && (g.t > after.t || (g.t == after.t && std::int32_t(f) > after.face));
        if (later && (g.t < best.t || (g.t == best.t && std::int32_t(f) < best.face))) best = {g.t, std::int32_t(f)};
      }
      ASSERT_EQ(h.face, best.face) << "ray " << n << " entry " << entry;
      if (!h.valid()) break;
      EXPECT_DOUBLE_EQ(h.t, best.t);
      ++hits;
      after = h;
    }
  }
  EXPECT_GT(hits, 200);
}

TEST(RenderRaycastReference, RestThroughAnyTransferMeshEqualsTheBoxTm) {
  // At rest every TM that covers the foreground maps each voxel to itself:
  // the images are identical, pixel for pixel, with cuts and hidden labels.
  const LabelGrid grid = stickFigure();
  Palette palette(grid.maxLabel());
  palette.hide("1");
  const TetMesh box = boxTransferMesh(grid);
  const RaycastMesh boxMesh = buildRaycastMesh(box, grid.geometry());
  const RaycastFrame boxFrame = prepareRaycastFrame(boxMesh, box.positions);
  for (const char* spec : {"azimuth=25,elevation=15", "azimuth=-100,elevation=-30"}) {
    const Camera camera = sceneCamera(boxFrame, spec, 160, 120);
    for (const char* cut : {"", "y<48"}) {
      CuttingPlanes cuts;
      if (*cut) cuts.add(cut);
      const Rendered expected = renderReference(grid, boxMesh, box.positions, camera, cuts, palette);
      EXPECT_GT(countNotBackground(expected.image, RaycastShading{}.background), 400u) << spec << " cut " << cut;
      for (int factor : {1, 2, 5}) {
        const TetMesh rest = coarseVoxelTransferMesh(grid, factor);
        const Rendered r = renderReference(grid, buildRaycastMesh(rest, grid.geometry()), rest.positions, camera, cuts, palette);
        EXPECT_EQ(compareImages(r.image, expected.image, 0).differing, 0u) << spec << " cut " << cut << " factor " << factor;
      }
    }
  }
}

TEST(RenderRaycastReference, PosesMatchTheRasterizedGridWithinTheStatedBound) {
  // Through a coarse voxel TM and through the pipeline's transfer mesh
  // (CGAL Mesh_3, boundary close to the voxels: more grazing rays).
  const LabelGrid grid = stickFigure();
  for (const TetMesh& rest : {coarseVoxelTransferMesh(grid, 3),
                              buildTransferMesh(binaryGroupGrid(grid), defaultSizingField(grid.geometry()))}) {
    std::size_t total = 0;
    for (test::Deformation d : {test::Deformation::Rotate, test::Deformation::Twist, test::Deformation::Bend})
      for (const char* cut : {"", "y<40", "plane=1,0,-0.5,-80"}) {
        const std::size_t n = poseVersusRasterizedGrid(grid, rest, d, "azimuth=20,elevation=10", cut, 160, 120);
        EXPECT_LE(double(n), kRasterizedBound * 160 * 120) << rest.tetCount() << " tets, " << test::deformationName(d) << " cut " << cut;
        total += n;
      }
    EXPECT_LE(double(total), 0.5 * kRasterizedBound * 9 * 160 * 120) << rest.tetCount() << " tets";
  }
}

TEST(RenderRaycastReference, AmPhantomPosesMatchTheRasterizedGrid) {
  const TetMesh rest = coarseVoxelTransferMesh(amPhantom(), test::kGoldenTmFactor);
  for (const test::GoldenScene& s : test::goldenScenes()) {
    if (s.deformation == test::Deformation::Rest) continue;
    const std::size_t n = poseVersusRasterizedGrid(amPhantom(), rest, s.deformation, s.camera, s.cut, test::kGoldenWidth, test::kGoldenHeight);
    EXPECT_LE(double(n), kRasterizedBound * test::kGoldenWidth * test::kGoldenHeight) << s.name;
  }
}

TEST(RenderRaycastReference, CutsAndHiddenLabelsAreHonoured) {
  const LabelGrid grid = stickFigure();
  const TetMesh rest = coarseVoxelTransferMesh(grid, 3);
  const RaycastMesh mesh = buildRaycastMesh(rest, grid.geometry());
  const RaycastFrame frame = prepareRaycastFrame(mesh, test::deform(rest.positions, grid.geometry(), test::Deformation::Twist));
  const auto factors = computeTetFactors(mesh, frame);
  Palette palette(grid.maxLabel());
  palette.hide("1,7");  // trunk and heart: the arms and legs remain
  CuttingPlanes cuts;
  cuts.add("x>20");
  cuts.add("plane=0,0.3,1,300");
  const RaycastView view = makeRaycastView(frame, sceneCamera(frame, "azimuth=40,elevation=20", 96, 72), cuts);
  std::size_t hits = 0;
  for (int y = 0; y < 72; ++y)
    for (int x = 0; x < 96; ++x) {
      const RayResult r = traceRayReference(grid, mesh, frame, factors, view, palette, view.eye, view.direction(x, y), {});
      if (!r.hit) continue;
      ++hits;
      EXPECT_TRUE(palette.visible(r.label));
      EXPECT_NE(r.label, 1);
      EXPECT_FALSE(cuts.removes(frame.toGrid(Eigen::Vector3d(double(r.cell[0]), double(r.cell[1]), double(r.cell[2])))));
    }
  EXPECT_GT(hits, 100u);
  // Hiding every label leaves the background.
  Palette none(grid.maxLabel());
  none.hide("1-" + std::to_string(grid.maxLabel()));
  const RgbImage empty = raycastReference(grid, mesh, frame, view, none);
  EXPECT_EQ(countNotBackground(empty, RaycastShading{}.background), 0u);
}

TEST(RenderRaycastReference, LooksAwayAndIsDeterministic) {
  const LabelGrid grid = stickFigure();
  const TetMesh rest = coarseVoxelTransferMesh(grid, 3);
  const RaycastMesh mesh = buildRaycastMesh(rest, grid.geometry());
  const RaycastFrame frame = prepareRaycastFrame(mesh, rest.positions);
  const Palette palette(grid.maxLabel());
  const Eigen::Vector3d c = frame.toGrid(0.5 * (frame.cellsLo + frame.cellsHi));
  Camera away;
  away.eye = c + Eigen::Vector3d(0, -1000, 0);
  away.target = c + Eigen::Vector3d(0, -2000, 0);
  away.width = 64;
  away.height = 48;
  EXPECT_EQ(countNotBackground(raycastReference(grid, mesh, frame, makeRaycastView(frame, away, {}), palette), RaycastShading{}.background), 0u);
  const RaycastView view = makeRaycastView(frame, sceneCamera(frame, "azimuth=10", 64, 48), {});
  const RgbImage a = raycastReference(grid, mesh, frame, view, palette);
  EXPECT_EQ(compareImages(a, raycastReference(grid, mesh, frame, view, palette), 0).differing, 0u);
  EXPECT_GT(countNotBackground(a, RaycastShading{}.background), 100u);
}

TEST(RenderRaycastReference, BadMeshesAndPositionsAreInputErrors) {
  const LabelGrid grid = stickFigure();
  TetMesh flat;
  flat.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  flat.tets = {{0, 1, 2, 3}};
  flat.labels = {1};
  EXPECT_THROW(buildRaycastMesh(flat, grid.geometry()), InputError);
  TetMesh badIndex = boxTransferMesh(grid);
  badIndex.tets[0][2] = 99;
  EXPECT_THROW(buildRaycastMesh(badIndex, grid.geometry()), InputError);
  EXPECT_THROW(buildRaycastMesh(TetMesh{}, grid.geometry()), InputError);

  const TetMesh box = boxTransferMesh(grid);
  const RaycastMesh mesh = buildRaycastMesh(box, grid.geometry());
  std::vector<Eigen::Vector3d> p = box.positions;
  p.pop_back();
  EXPECT_THROW(prepareRaycastFrame(mesh, p), InputError);
  p = box.positions;
  p[3][1] = std::nan("");
  EXPECT_THROW(prepareRaycastFrame(mesh, p), InputError);
  EXPECT_THROW(boxTransferMesh(LabelGrid(grid.geometry(), 0)), InputError);
}

TEST(RenderRaycastReference, GoldenImages) {
  // Regenerate with VOX_UPDATE_GOLDEN=1 (then look at the PNGs).
  const bool update = std::getenv("VOX_UPDATE_GOLDEN") != nullptr;
  const LabelGrid& grid = amPhantom();
  const OrganTable organs = OrganTable::read(test::assetPath("icrp110_am_organs.dat"));
  const Palette palette = Palette::fromOrgans(organs, grid.maxLabel());
  const TetMesh rest = coarseVoxelTransferMesh(grid, test::kGoldenTmFactor);
  const RaycastMesh mesh = buildRaycastMesh(rest, grid.geometry());
  for (const test::GoldenScene& s : test::goldenScenes()) {
    const auto posed = test::deform(rest.positions, grid.geometry(), s.deformation);
    CuttingPlanes cuts;
    if (!s.cut.empty()) cuts.add(s.cut);
    const RaycastFrame frame = prepareRaycastFrame(mesh, posed);
    const Rendered r = renderReference(grid, mesh, posed, sceneCamera(frame, s.camera, test::kGoldenWidth, test::kGoldenHeight), cuts, palette);
    const std::string path = test::assetPath("golden/raycast_" + s.name + ".png");
    if (update) writePng(path, r.image);
    const ImageDifference d = compareImages(r.image, readPng(path), 5);
    EXPECT_LE(d.differingFraction(), 0.001) << s.name << ": " << d.differing << " pixels differ";
    EXPECT_GT(countNotBackground(r.image, RaycastShading{}.background), 3000u) << s.name;
  }
}

}  // namespace
}  // namespace vox
