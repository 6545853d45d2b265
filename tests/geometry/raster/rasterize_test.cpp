// CPU reference rasterizer: the tie rule and the barycentric mapping against
// an independent per-voxel check, identity reproduces the input, slab and
// window independence, supersampling's tie rule, bad input.

#include "geometry/raster/lattice_tets.h"
#include "geometry/raster/rasterize.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/label_stats.h"
#include "geometry/parallel.h"
#include "geometry/synth.h"
#include "tests/support/deformation_fixtures.h"
#include "tests/support/test_environment.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <limits>
#include <map>

namespace vox {
namespace {

using test::coveringTransferMesh;
using test::deformPositions;
using test::gridCentre;

// Barycentric coordinates by a direct 3x3 solve in mm, independent of the
// canonical face planes.
Eigen::Vector4d solveBarycentric(const std::array<Eigen::Vector3d, 4>& v, const Eigen::Vector3d& p) {
  Eigen::Matrix3d m;
  m << v[1] - v[0], v[2] - v[0], v[3] - v[0];
  const Eigen::Vector3d l = m.fullPivLu().solve(p - v[0]);
  return {1.0 - l.sum(), l[0], l[1], l[2]};
}

// Independent rasterization: per output voxel, the lowest tet whose directly
// solved barycentrics are all > -tol, the label through GridGeometry::voxelAt
// in mm. Voxels whose winner depends on a barycentric within tol of 0 are
// reported as ambiguous and skipped by the comparison.
struct BruteForce {
  LabelGrid grid;
  std::vector<char> ambiguous;
};
BruteForce bruteForceRasterize(const LabelGrid& source, const TetMesh& rest, const std::vector<Eigen::Vector3d>& deformed,
                               double tol) {
  BruteForce r{LabelGrid(deformedGridGeometry(source.geometry(), deformed)), {}};
  const GridGeometry& g = r.grid.geometry();
  r.ambiguous.assign(std::size_t(g.voxelCount()), 0);
  std::vector<std::int32_t> winner(std::size_t(g.voxelCount()), -1);
  for (std::size_t t = 0; t < rest.tetCount(); ++t) {
    std::array<Eigen::Vector3d, 4> d, s;
    Eigen::Vector3d lo = deformed[std::size_t(rest.tets[t][0])], hi = lo;
    for (int k = 0; k < 4; ++k) {
      d[std::size_t(k)] = deformed[std::size_t(rest.tets[t][std::size_t(k)])];
      s[std::size_t(k)] = rest.positions[std::size_t(rest.tets[t][std::size_t(k)])];
      lo = lo.cwiseMin(d[std::size_t(k)]);
      hi = hi.cwiseMax(d[std::size_t(k)]);
    }
    const Eigen::Vector3d a = g.continuousIndex(lo), b = g.continuousIndex(hi);
    for (std::int64_t k = std::max<std::int64_t>(0, std::int64_t(std::floor(a.z())) - 1);
         k <= std::min<std::int64_t>(g.dims[2] - 1, std::int64_t(std::ceil(b.z())) + 1); ++k)
      for (std::int64_t j = std::max<std::int64_t>(0, std::int64_t(std::floor(a.y())) - 1);
           j <= std::min<std::int64_t>(g.dims[1] - 1, std::int64_t(std::ceil(b.y())) + 1); ++j)
        for (std::int64_t i = std::max<std::int64_t>(0, std::int64_t(std::floor(a.x())) - 1);
             i <= std::min<std::int64_t>(g.dims[0] - 1, std::int64_t(std::ceil(b.x())) + 1); ++i) {
          const std::size_t v = std::size_t(g.index(i, j, k));
          if (winner[v] >= 0) continue;
          const Eigen::Vector4d l = solveBarycentric(d, g.voxelCenter(i, j, k));
          if (l.minCoeff() < -tol) continue;
          if (l.minCoeff() <= tol) r.ambiguous[v] = 1;
          winner[v] = std::int32_t(t);
          const Eigen::Vector3d p = l[0] * s[0] + l[1] * s[1] + l[2] * s[2] + l[3] * s[3];
          Index3 src;
          r.grid.labels()[v] = source.geometry().voxelAt(p, src) ? source.at(src[0], src[1], src[2]) : Label(0);
          // A source position this close to a voxel boundary may round either way.
          const Eigen::Vector3d c = source.geometry().continuousIndex(p);
          for (int ax = 0; ax < 3; ++ax)
            if (std::abs(c[ax] - std::floor(c[ax]) - 0.5) < 1e-9) r.ambiguous[v] = 1;
        }
  }
  return r;
}

LabelGrid stickFigure() {
  LabelGrid grid = synthesize(SynthKind::StickFigure, 40);
  grid.geometry().spacing = {1.5, 1.25, 2.0};
  grid.geometry().origin = {-20.0, 7.0, 3.0};
  return grid;
}

TEST(RasterizeCpu, EqualsIndependentCheckUnderNonRigidMaps) {
  const LabelGrid source = stickFigure();
  const TetMesh tm = coveringTransferMesh(source, 3);
  const Eigen::Vector3d c = gridCentre(source.geometry());
  const std::map<std::string, test::Deformation> maps = {
      {"bend", test::bend(c, 40.0)},
      {"twist", test::twist(c, 1.5)},
      {"rotation", test::rotation(c, {1.0, 2.0, 0.5}, 33.0)},
  };
  for (const auto& [name, f] : maps) {
    const auto deformed = deformPositions(tm.positions, f);
    const LabelGrid out = rasterizeDeformedGrid(source, tm, deformed);
    const BruteForce ref = bruteForceRasterize(source, tm, deformed, 1e-9);
    ASSERT_EQ(out.dims(), ref.grid.dims()) << name;
    EXPECT_TRUE(out.geometry().origin.isApprox(ref.grid.geometry().origin)) << name;
    std::int64_t compared = 0, differ = 0, foreground = 0;
    for (std::size_t v = 0; v < out.labels().size(); ++v) {
      foreground += out.labels()[v] != 0;
      if (ref.ambiguous[v]) continue;
      ++compared;
      differ += out.labels()[v] != ref.grid.labels()[v];
    }
    EXPECT_EQ(differ, 0) << name;
    EXPECT_GT(compared, out.voxelCount() * 9 / 10) << name;
    EXPECT_GT(foreground, 1000) << name;
  }
}

TEST(RasterizeCpu, TieRuleIsLowestTetIndexAndWatertight) {
  // Every voxel centre of a six-tet mesh lies on the main diagonal shared by
  // its voxel's six tets (and on no other tet): the winner must be the first
  // of them.
  GridGeometry g;
  g.dims = {6, 5, 4};
  LabelGrid grid(g, 1);
  const TetMesh tm = tetrahedralizeVoxels(grid, {.includeBackground = false});
  const RasterizationPlan plan(g, tm, tm.positions);
  ASSERT_EQ(plan.output().dims, g.dims);
  const SlabTets slab = plan.slab(0, g.dims[2]);
  std::vector<std::uint32_t> state(std::size_t(g.voxelCount()));
  locateLatticePoints(plan.tets(), slab, plan.lattice(), state.data(), 2);
  for (std::int64_t v = 0; v < g.voxelCount(); ++v) {
    ASSERT_NE(state[std::size_t(v)], kNoTet) << v;
    EXPECT_EQ(slab.tets[state[std::size_t(v)]], std::int32_t(6 * v)) << v;
  }
  // Rotated by an angle that puts centres near (not on) faces: still no hole
  // inside, and every centre takes the lowest tet that contains it.
  const auto deformed = deformPositions(tm.positions, test::rotation(gridCentre(g), {0.3, 0.2, 1.0}, 17.0));
  const RasterizationPlan rotated(g, tm, deformed);
  const SlabTets all = rotated.slab(0, rotated.output().dims[2]);
  std::vector<std::uint32_t> located(std::size_t(rotated.lattice().voxelCount()));
  locateLatticePoints(rotated.tets(), all, rotated.lattice(), located.data(), 2);
  for (std::int64_t v = 0; v < rotated.lattice().voxelCount(); ++v) {
    const Index3 q = rotated.lattice().ijk(v);
    std::int32_t first = -1;
    for (std::size_t t = 0; t < rotated.tets().size() && first < 0; ++t)
      if (rotated.tets()[t].contains(std::int32_t(q[0]), std::int32_t(q[1]), std::int32_t(q[2]))) first = std::int32_t(t);
    const std::int32_t got = located[std::size_t(v)] == kNoTet ? -1 : all.tets[located[std::size_t(v)]];
    ASSERT_EQ(got, first) << v;
  }
}

TEST(RasterizeCpu, LatticeTetsAreTheSameOnAnyThreadCount) {
  const LabelGrid grid = synthesize(SynthKind::JunctionSphere, 41);
  const TetMesh tm = coveringTransferMesh(grid, 2);
  ASSERT_GT(tm.tetCount(), 3u * 4096u);  // several ranges of the parallel loop
  const auto deformed = deformPositions(tm.positions, test::twist(gridCentre(grid.geometry()), 1.5));
  std::vector<LatticeTet> one;
  {
    const ScopedWorkerThreads scope(1);
    one = latticeTets(grid.geometry(), deformed, tm.tets);
  }
  const ScopedWorkerThreads scope(3);
  const std::vector<LatticeTet> three = latticeTets(grid.geometry(), deformed, tm.tets);
  ASSERT_EQ(three.size(), one.size());
  for (std::size_t t = 0; t < one.size(); ++t) {
    ASSERT_EQ(three[t].lo, one[t].lo) << t;
    ASSERT_EQ(three[t].hi, one[t].hi) << t;
    for (std::size_t k = 0; k < 4; ++k) {
      ASSERT_EQ(three[t].normal[k], one[t].normal[k]) << t;
      ASSERT_EQ(three[t].offset[k], one[t].offset[k]) << t;
      ASSERT_EQ(three[t].anchor[k], one[t].anchor[k]) << t;
    }
  }
}

TEST(RasterizeCpu, IdentityReproducesForeground) {
  for (SynthKind kind : {SynthKind::StickFigure, SynthKind::JunctionSphere}) {
    LabelGrid source = synthesize(kind, 36);
    source.geometry().spacing = {1.1, 0.9, 2.5};
    for (int factor : {1, 4}) {
      const TetMesh tm = coveringTransferMesh(source, factor);
      for (int samples : {1, 2, 3}) {
        const LabelGrid out = rasterizeDeformedGrid(source, tm, tm.positions, {.samples = samples});
        // Output lattice = source lattice shifted by an integer offset.
        const Eigen::Vector3d offset = source.geometry().continuousIndex(out.geometry().origin);
        ASSERT_TRUE(offset.isApprox(offset.array().round().matrix())) << offset.transpose();
        std::int64_t mismatched = 0, foreground = 0;
        for (std::int64_t k = 0; k < source.dims()[2]; ++k)
          for (std::int64_t j = 0; j < source.dims()[1]; ++j)
            for (std::int64_t i = 0; i < source.dims()[0]; ++i) {
              const Label l = source.at(i, j, k);
              const Label o = out.atOr(i - std::int64_t(std::lround(offset.x())), j - std::int64_t(std::lround(offset.y())),
                                       k - std::int64_t(std::lround(offset.z())));
              foreground += l != 0;
              if (l != 0) mismatched += o != l;
            }
        EXPECT_EQ(mismatched, 0) << synthKindName(kind) << " factor " << factor << " samples " << samples;
        EXPECT_GT(foreground, 1000);
      }
    }
  }
}

TEST(RasterizeCpu, IdentityReproducesTheAmPhantom) {
  const LabelGrid source = readGrid(test::assetPath("icrp110_am.nii.gz"));
  const TetMesh tm = coveringTransferMesh(source, 4);
  const LabelGrid out = rasterizeDeformedGrid(source, tm, tm.positions);
  const Eigen::Vector3d offset = source.geometry().continuousIndex(out.geometry().origin);
  const Index3 o{std::lround(offset.x()), std::lround(offset.y()), std::lround(offset.z())};
  // Voxel for voxel: every source voxel inside the output grid keeps its
  // label (background included: the mesh covers exactly the blocks holding
  // foreground), and no foreground lies outside it.
  std::int64_t mismatched = 0, foreground = 0;
  for (std::int64_t k = 0; k < source.dims()[2]; ++k)
    for (std::int64_t j = 0; j < source.dims()[1]; ++j)
      for (std::int64_t i = 0; i < source.dims()[0]; ++i) {
        const Label l = source.at(i, j, k);
        foreground += l != 0;
        if (out.geometry().contains(i - o[0], j - o[1], k - o[2]) || l != 0) mismatched += out.atOr(i - o[0], j - o[1], k - o[2]) != l;
      }
  EXPECT_EQ(mismatched, 0);
  EXPECT_GT(foreground, 1000000);
}

TEST(RasterizeCpu, OutputGeometryAlignedToSourceLattice) {
  const LabelGrid source = stickFigure();
  const TetMesh tm = coveringTransferMesh(source, 2);
  const Eigen::Vector3d shift = source.spacing().cwiseProduct(Eigen::Vector3d(3, -2, 5));
  const auto moved = deformPositions(tm.positions, [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(p + shift); });
  const GridGeometry a = deformedGridGeometry(source.geometry(), tm.positions);
  const GridGeometry b = deformedGridGeometry(source.geometry(), moved);
  EXPECT_EQ(a.dims, b.dims);
  EXPECT_TRUE((b.origin - a.origin - shift).norm() < 1e-9);
  EXPECT_TRUE(b.spacing == source.spacing());
  // An integer translation moves every label with it.
  const LabelGrid ra = rasterizeDeformedGrid(source, tm, tm.positions);
  const LabelGrid rb = rasterizeDeformedGrid(source, tm, moved);
  EXPECT_EQ(ra.labels(), rb.labels());
}

TEST(RasterizeCpu, RigidRotationKeepsLabelVolumes) {
  const LabelGrid source = synthesize(SynthKind::NestedSpheres, 48);
  const TetMesh tm = coveringTransferMesh(source, 2);
  const auto deformed = deformPositions(tm.positions, test::rotation(gridCentre(source.geometry()), {1, 1, 0}, 30.0));
  const LabelStats before = computeLabelStats(source);
  for (int samples : {1, 3}) {
    const LabelStats after = computeLabelStats(rasterizeDeformedGrid(source, tm, deformed, {.samples = samples}));
    for (Label l = 1; l < before.counts.size(); ++l) {
      if (before.counts[l] == 0) continue;
      ASSERT_LT(l, after.counts.size());
      EXPECT_NEAR(double(after.counts[l]) / double(before.counts[l]), 1.0, 0.02) << "label " << l << " samples " << samples;
    }
  }
}

TEST(RasterizeCpu, SlabsAndSourceWindowsDoNotChangeTheResult) {
  const LabelGrid source = stickFigure();
  const TetMesh tm = coveringTransferMesh(source, 3);
  const auto deformed = deformPositions(tm.positions, test::bend(gridCentre(source.geometry()), 35.0));
  for (int samples : {1, 2}) {
    const LabelGrid whole = rasterizeDeformedGrid(source, tm, deformed, {.samples = samples});
    const RasterizationPlan plan(source.geometry(), tm, deformed, samples);
    LabelGrid pieced(plan.output());
    const std::int64_t nz = plan.output().dims[2], sourceSlice = source.geometry().sliceVoxels();
    for (std::int64_t z0 = 0; z0 < nz; z0 += 5) {
      const std::int64_t z1 = std::min(nz, z0 + 5);
      const SlabTets slab = plan.slab(z0, z1);
      std::vector<std::uint32_t> state(std::size_t((z1 - z0) * plan.samplesPerOutputSlice()));
      locateLatticePoints(plan.tets(), slab, plan.lattice(), state.data(), 2);
      const auto range = plan.sourceSlices(slab);
      for (std::int64_t w0 = range.first; w0 < range.last; w0 += 3) {
        const std::int64_t w1 = std::min(range.last, w0 + 3);
        resolveSamples(plan, slab, source.data() + w0 * sourceSlice, w0, w1, state.data(), 1);
      }
      reduceSamples(plan, slab, state.data(), pieced.data() + z0 * plan.output().sliceVoxels(), 2);
    }
    EXPECT_EQ(pieced.labels(), whole.labels()) << "samples " << samples;
  }
}

TEST(RasterizeCpu, SlabEngineWithSmallLimitsEqualsInCore) {
  const LabelGrid source = stickFigure();
  const TetMesh tm = coveringTransferMesh(source, 3);
  const auto deformed = deformPositions(tm.positions, test::twist(gridCentre(source.geometry()), 2.0));
  const LabelGrid whole = rasterizeDeformedGrid(source, tm, deformed);
  const RasterizationPlan plan(source.geometry(), tm, deformed);
  LabelGridSlices reader(source);
  // Slabs of 3 output slices, windows of 4 source slices: several windows per slab.
  CpuSlabRasterizer engine(plan, reader,
                           {.slabSamples = 3 * plan.samplesPerOutputSlice(), .windowVoxels = 4 * source.geometry().sliceVoxels()});
  ASSERT_EQ(engine.slabSlices(), 3);
  LabelGrid pieced(engine.outputGeometry());
  const std::int64_t nz = pieced.dims()[2];
  for (std::int64_t z0 = 0; z0 < nz; z0 += 3)
    engine.rasterizeSlab(z0, std::min(nz, z0 + 3), pieced.data() + z0 * pieced.geometry().sliceVoxels());
  EXPECT_EQ(pieced.labels(), whole.labels());
}

TEST(RasterizeCpu, SourceWindowsCoverWhatIsNeeded) {
  using W = std::vector<SliceRange>;
  EXPECT_EQ(sourceWindows({}, {0, 10}, 5, 100), W{});
  EXPECT_EQ(sourceWindows({3, 8}, {0, 10}, 5, 100), (W{{0, 10}}));        // resident
  EXPECT_EQ(sourceWindows({3, 8}, {0, 5}, 10, 100), (W{{3, 13}}));        // read ahead
  EXPECT_EQ(sourceWindows({95, 99}, {}, 10, 100), (W{{90, 100}}));       // clipped at the end
  EXPECT_EQ(sourceWindows({3, 8}, {}, 500, 100), (W{{0, 100}}));         // whole source
  EXPECT_EQ(sourceWindows({3, 14}, {}, 5, 100), (W{{3, 8}, {8, 13}, {13, 14}}));
}

TEST(RasterizeCpu, SupersamplingTiesGoToTheLowestLabel) {
  // Stripes of labels 9 and 5 along x, the mesh translated by half a voxel:
  // with k = 2 every voxel's samples split 4:4 between two neighbours.
  GridGeometry g;
  g.dims = {8, 4, 4};
  LabelGrid source(g);
  for (std::int64_t k = 0; k < 4; ++k)
    for (std::int64_t j = 0; j < 4; ++j)
      for (std::int64_t i = 0; i < 8; ++i) source.at(i, j, k) = i % 2 ? 5 : 9;
  const TetMesh tm = tetrahedralizeVoxels(source);
  const auto moved = deformPositions(tm.positions, [](const Eigen::Vector3d& p) { return Eigen::Vector3d(p + Eigen::Vector3d(0.5, 0, 0)); });
  const LabelGrid k1 = rasterizeDeformedGrid(source, tm, moved, {.samples = 1});
  const LabelGrid k2 = rasterizeDeformedGrid(source, tm, moved, {.samples = 2});
  // The deformed mesh spans x in [0, 8]: output centres x = 0..8.
  ASSERT_EQ(k2.dims()[0], 9);
  for (std::int64_t k = 0; k < 4; ++k)
    for (std::int64_t j = 0; j < 4; ++j)
      for (std::int64_t i = 0; i < 9; ++i) {
        // Centre i maps back to i - 0.5, whose nearest centre rounds up to i.
        EXPECT_EQ(k1.at(i, j, k), source.atOr(i, j, k)) << i;
        // Samples i -+ 0.25 map to i - 0.75 and i - 0.25: voxels i - 1 and i,
        // or no tet at all beyond the mesh (label 0): a 4:4 tie everywhere.
        const Label expect = std::min(source.atOr(i - 1, j, k), source.atOr(i, j, k));
        EXPECT_EQ(k2.at(i, j, k), expect) << i;
      }
}

TEST(RasterizeCpu, BadInputIsReported) {
  const LabelGrid source = synthesize(SynthKind::NestedSpheres, 12);
  const TetMesh tm = coveringTransferMesh(source, 2);
  auto shorter = tm.positions;
  shorter.pop_back();
  EXPECT_THROW(rasterizeDeformedGrid(source, tm, shorter), InputError);
  auto nan = tm.positions;
  nan[3].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(rasterizeDeformedGrid(source, tm, nan), InputError);
  EXPECT_THROW(rasterizeDeformedGrid(source, tm, tm.positions, {.samples = 0}), InputError);
  EXPECT_THROW(rasterizeDeformedGrid(source, tm, tm.positions, {.samples = 5}), InputError);
  TetMesh broken = tm;
  broken.tets[0][2] = std::int32_t(tm.positions.size());
  EXPECT_THROW(rasterizeDeformedGrid(source, broken, tm.positions), InputError);
}

}  // namespace
}  // namespace vox
