// Label volumes through a deformation (sum of Jacobian determinants over a
// label's source voxels) and the correction of the posed grid's counts:
// identity and uniform scaling give the expected volumes, a rotated and a
// twisted junction sphere end with every label within one voxel of its
// volume, relabelling only voxels at label boundaries, the same for any
// thread count; enclosed gaps are filled; a grid of another geometry is
// rejected.

#include "geometry/deform/solve/label_volumes.h"
#include "geometry/raster/rasterize.h"
#include "geometry/error.h"
#include "geometry/label_stats.h"
#include "geometry/synth.h"
#include "tests/support/deformation_fixtures.h"

#include <gtest/gtest.h>

#include <limits>

#include <cmath>
#include <iostream>

namespace vox {
namespace {

using test::coveringTransferMesh;
using test::deformPositions;
using test::gridCentre;

struct Scene {
  LabelGrid source;
  TetMesh rest;
};
const Scene& junctionSphere() {
  static const Scene scene = [] {
    Scene s{synthesize(SynthKind::JunctionSphere, 40), {}};
    s.rest = coveringTransferMesh(s.source, 2);
    return s;
  }();
  return scene;
}

TEST(LabelVolumes, IdentityGivesTheSourceCountsAndScalingTheirMultiple) {
  const Scene& s = junctionSphere();
  const std::vector<std::uint64_t> counts = computeLabelStats(s.source).counts;
  const std::vector<double> identity = deformedLabelVolumes(s.source, s.rest, s.rest.positions);
  const double scale = 1.1;
  const Eigen::Vector3d c = gridCentre(s.source.geometry());
  const std::vector<double> scaled = deformedLabelVolumes(
      s.source, s.rest, deformPositions(s.rest.positions, [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(c + scale * (p - c)); }));
  ASSERT_EQ(identity.size(), counts.size());
  for (std::size_t l = 1; l < counts.size(); ++l) {
    EXPECT_NEAR(identity[l], double(counts[l]), 1e-9 * double(counts[l])) << "label " << l;
    EXPECT_NEAR(scaled[l], std::pow(scale, 3) * double(counts[l]), 1e-9 * double(counts[l])) << "label " << l;
  }
}

TEST(LabelVolumes, PrecountedTetVoxelsGiveTheSameVolumes) {
  // The viewer's live figures: voxels per (tet, label) counted once, then
  // one pass over the tets per frame.
  const Scene& s = junctionSphere();
  const Eigen::Vector3d c = gridCentre(s.source.geometry());
  const std::vector<Eigen::Vector3d> twisted = deformPositions(s.rest.positions, [&](const Eigen::Vector3d& p) {
    const double a = 0.01 * (p.z() - c.z());
    const Eigen::Vector3d d = p - c;
    return Eigen::Vector3d(c.x() + std::cos(a) * d.x() - std::sin(a) * d.y(), c.y() + std::sin(a) * d.x() + std::cos(a) * d.y(),
                           p.z() + 0.05 * d.z());
  });
  const TetLabelVoxels voxels = tetLabelVoxels(s.source, s.rest);
  std::uint64_t counted = 0;
  for (std::uint32_t n : voxels.counts) counted += n;
  const std::vector<double> direct = deformedLabelVolumes(s.source, s.rest, twisted);
  const std::vector<double> precounted = deformedLabelVolumes(voxels, s.rest, twisted);
  const std::vector<double> rest = deformedLabelVolumes(voxels, s.rest, s.rest.positions);
  ASSERT_EQ(direct.size(), precounted.size());
  double restTotal = 0.0;
  for (std::size_t l = 0; l < direct.size(); ++l) {
    EXPECT_NEAR(precounted[l], direct[l], 1e-9 * std::max(1.0, direct[l])) << "label " << l;
    restTotal += rest[l];
  }
  EXPECT_NEAR(restTotal, double(counted), 1e-6);
  EXPECT_GT(counted, 0u);
  EXPECT_THROW(deformedLabelVolumes(voxels, s.rest, std::vector<Eigen::Vector3d>(3)), InputError);
}

// Rasterizes, corrects with `threads` threads, checks every label is within one
// voxel of its volume; returns the corrected grid.
LabelGrid correctedGrid(const Scene& s, const std::vector<Eigen::Vector3d>& deformed, int threads, const char* what) {
  LabelGrid posed = rasterizeDeformedGrid(s.source, s.rest, deformed);
  const std::vector<double> targets = deformedLabelVolumes(s.source, s.rest, deformed, threads);
  const std::vector<std::uint64_t> nearest = computeLabelStats(posed).counts;
  const LabelVolumeCorrection c = preserveLabelVolumes(posed, s.source, s.rest, deformed, targets, threads);
  const std::vector<std::uint64_t> counts = computeLabelStats(posed).counts;
  double foreground = 0.0;
  for (std::size_t l = 1; l < targets.size(); ++l) {
    const double n = l < counts.size() ? double(counts[l]) : 0.0;
    EXPECT_LE(std::abs(n - targets[l]), 1.0) << what << ": label " << l << " has " << n << " voxels for a volume of "
                                             << targets[l] << " (nearest neighbour: " << nearest[l] << ")";
    foreground += targets[l];
  }
  EXPECT_LE(c.deviationAfter, c.deviationBefore);
  EXPECT_LE(c.relabelled, c.candidates);
  EXPECT_LT(c.worstPercentAfter, c.worstPercentBefore) << what;
  // Only boundary voxels change, and few of them: under 5 % of the foreground here (a 40-voxel sphere).
  EXPECT_LT(double(c.relabelled), 0.05 * foreground) << what;
  std::cout << "[ stats    ] " << what << ": " << c.candidates << " boundary voxels, " << c.relabelled << " relabelled in "
            << c.sweeps << " sweeps; deviation " << c.deviationBefore << " -> " << c.deviationAfter
            << " voxels, worst label " << c.worstPercentBefore << " % -> " << c.worstPercentAfter << " %\n";
  return posed;
}

TEST(LabelVolumes, RotatedJunctionSphereKeepsEveryLabelWithinOneVoxel) {
  const Scene& s = junctionSphere();
  const auto deformed =
      deformPositions(s.rest.positions, test::rotation(gridCentre(s.source.geometry()), {0.3, 0.2, 1.0}, 30.0));
  const LabelGrid one = correctedGrid(s, deformed, 1, "rotation 30 deg, 1 thread");
  const LabelGrid two = correctedGrid(s, deformed, 2, "rotation 30 deg, 2 threads");
  EXPECT_EQ(one.labels(), two.labels());
}

TEST(LabelVolumes, TwistedJunctionSphereKeepsEveryLabelWithinOneVoxel) {
  const Scene& s = junctionSphere();
  correctedGrid(s, deformPositions(s.rest.positions, test::twist(gridCentre(s.source.geometry()), 1.5)), 2, "twist");
}

// Half of the sphere stays where it is, the other half is squashed: the
// correction relabels only voxels of tets that moved, so every voxel of the
// still half keeps the source's label.
TEST(LabelVolumes, StillTissueKeepsItsLabels) {
  const Scene& s = junctionSphere();
  const GridGeometry& g = s.source.geometry();
  const double mid = gridCentre(g).z();
  std::vector<Eigen::Vector3d> deformed = s.rest.positions;
  for (Eigen::Vector3d& p : deformed)
    if (p.z() > mid) p.z() = mid + 0.8 * (p.z() - mid);
  LabelGrid posed = rasterizeDeformedGrid(s.source, s.rest, deformed);
  const std::vector<double> targets = deformedLabelVolumes(s.source, s.rest, deformed);
  const LabelVolumeCorrection c = preserveLabelVolumes(posed, s.source, s.rest, deformed, targets);
  EXPECT_GT(c.relabelled, 0u);
  EXPECT_GT(c.still, 0u);
  // Output voxels below the lowest vertex that moved are the source's.
  double lowest = std::numeric_limits<double>::infinity();
  for (std::size_t v = 0; v < deformed.size(); ++v)
    if ((deformed[v] - s.rest.positions[v]).norm() > 0.0) lowest = std::min(lowest, s.rest.positions[v].z());
  const GridGeometry& out = posed.geometry();
  std::int64_t compared = 0;
  for (std::int64_t k = 0; k < out.dims[2]; ++k)
    for (std::int64_t j = 0; j < out.dims[1]; ++j)
      for (std::int64_t i = 0; i < out.dims[0]; ++i) {
        const Eigen::Vector3d p = out.voxelCenter(i, j, k);
        Index3 v;
        if (p.z() >= lowest - 2.0 * g.spacing.z() || !g.voxelAt(p, v)) continue;
        ++compared;
        ASSERT_EQ(posed.at(i, j, k), s.source.at(v[0], v[1], v[2])) << "voxel " << i << " " << j << " " << k;
      }
  EXPECT_GT(compared, 1000);
}

// The scene's mesh without the tets whose centroid lies within 4 voxels of
// `hole` (a point inside the sphere).
TetMesh holedMesh(const Scene& s, const Eigen::Vector3d& hole) {
  const GridGeometry& g = s.source.geometry();
  TetMesh holed = s.rest;
  holed.tets.clear();
  for (const Tet& t : s.rest.tets) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const std::int32_t v : t) centroid += 0.25 * s.rest.positions[std::size_t(v)];
    if ((centroid - hole).cwiseQuotient(g.spacing).norm() >= 4.0) holed.tets.push_back(t);
  }
  holed.labels.assign(holed.tets.size(), 0);
  return holed;
}

// A gap inside the body, where no tet covers the posed grid (the sliding
// surfaces of an articulated pose parting), is closed with the labels
// around it; background outside the body stays. A label flagged as behind
// (a bone) fills only what the others do not reach.
TEST(LabelVolumes, EnclosedGapsAreFilledWithTheTissueAround) {
  const Scene& s = junctionSphere();
  const GridGeometry& g = s.source.geometry();
  const Eigen::Vector3d c = gridCentre(g);
  // The mesh without the tets whose centroid lies within 4 voxels of a
  // point inside the sphere, off its centre: the posed grid (identity) has a
  // hole there.
  const TetMesh holed = holedMesh(s, c + Eigen::Vector3d(5.0, 3.0, 2.0).cwiseProduct(g.spacing));
  ASSERT_LT(holed.tets.size(), s.rest.tets.size());
  LabelGrid posed = rasterizeDeformedGrid(s.source, holed, holed.positions);
  const LabelGrid before = posed;
  // The source's label at each posed voxel (the posed grid may add a margin).
  const GridGeometry& out = posed.geometry();
  std::vector<Label> sourceAt(std::size_t(posed.voxelCount()), 0);
  for (std::int64_t k = 0; k < out.dims[2]; ++k)
    for (std::int64_t j = 0; j < out.dims[1]; ++j)
      for (std::int64_t i = 0; i < out.dims[0]; ++i) {
        Index3 v;
        if (g.voxelAt(out.voxelCenter(i, j, k), v)) sourceAt[std::size_t(out.index(i, j, k))] = s.source.at(v[0], v[1], v[2]);
      }
  std::int64_t holeVoxels = 0, outside = 0;
  for (std::int64_t v = 0; v < posed.voxelCount(); ++v) {
    holeVoxels += posed.data()[v] == 0 && sourceAt[std::size_t(v)] != 0;
    outside += sourceAt[std::size_t(v)] == 0;
  }
  ASSERT_GT(holeVoxels, 20);
  ASSERT_GT(outside, 0);
  const std::uint64_t filled = fillEnclosedGaps(posed, s.source, holed, holed.positions, 2);
  EXPECT_EQ(std::int64_t(filled), holeVoxels);
  std::int64_t agree = 0;
  for (std::int64_t v = 0; v < posed.voxelCount(); ++v) {
    const Label was = before.data()[v], now = posed.data()[v], rest = sourceAt[std::size_t(v)];
    if (was != 0) {
      ASSERT_EQ(now, was) << v;
    }
    if (rest == 0) {
      ASSERT_EQ(now, 0) << v;
    }
    if (was == 0 && rest != 0) {
      ASSERT_NE(now, 0) << v;
      agree += now == rest;
    }
  }
  EXPECT_GT(double(agree), 0.7 * double(holeVoxels));
  // The label that filled most, flagged as behind: it fills less; every
  // label flagged: as none.
  std::vector<std::int64_t> took(std::size_t(s.source.maxLabel()) + 1, 0);
  for (std::int64_t v = 0; v < posed.voxelCount(); ++v)
    if (before.data()[v] == 0 && posed.data()[v] != 0) ++took[posed.data()[v]];
  const auto most = Label(std::max_element(took.begin(), took.end()) - took.begin());
  std::vector<std::uint8_t> behind(took.size(), 0);
  behind[most] = 1;
  LabelGrid aside = before;
  EXPECT_EQ(fillEnclosedGaps(aside, s.source, holed, holed.positions, 2, behind), filled);
  std::int64_t tookAside = 0;
  for (std::int64_t v = 0; v < aside.voxelCount(); ++v) tookAside += before.data()[v] == 0 && aside.data()[v] == most;
  EXPECT_LT(tookAside, took[most]);
  LabelGrid all = before;
  fillEnclosedGaps(all, s.source, holed, holed.positions, 2, std::vector<std::uint8_t>(took.size(), 1));
  EXPECT_EQ(all.labels(), posed.labels());
  // The whole mesh: nothing to fill.
  LabelGrid whole = rasterizeDeformedGrid(s.source, s.rest, s.rest.positions);
  EXPECT_EQ(fillEnclosedGaps(whole, s.source, s.rest, s.rest.positions, 2), 0u);
}

// The correction that fills the gaps first, in its own pass over the posed
// lattice, gives what the fill and then the correction give.
TEST(LabelVolumes, TheCorrectionFillsTheGapsAsTheFillDoes) {
  const Scene& s = junctionSphere();
  const GridGeometry& g = s.source.geometry();
  const Eigen::Vector3d c = gridCentre(g);
  const TetMesh holed = holedMesh(s, c + Eigen::Vector3d(5.0, 3.0, 2.0).cwiseProduct(g.spacing));
  const auto deformed = deformPositions(holed.positions, test::rotation(c, {0, 0, 1}, 30.0));
  const LabelGrid posed = rasterizeDeformedGrid(s.source, holed, deformed);
  const std::vector<double> targets = deformedLabelVolumes(s.source, holed, deformed);
  std::vector<std::uint8_t> behind(std::size_t(s.source.maxLabel()) + 1, 0);
  behind[1] = 1;
  LabelGrid apart = posed;
  const std::uint64_t filled = fillEnclosedGaps(apart, s.source, holed, deformed, 2, behind);
  const LabelVolumeCorrection after = preserveLabelVolumes(apart, s.source, holed, deformed, targets, 2);
  for (const int threads : {1, 2}) {
    LabelGrid together = posed;
    const LabelVolumeCorrection both = preserveLabelVolumes(together, s.source, holed, deformed, targets, threads, true, behind);
    EXPECT_EQ(together.labels(), apart.labels()) << threads << " threads";
    EXPECT_EQ(both.gapsFilled, filled);
    EXPECT_EQ(both.relabelled, after.relabelled);
    EXPECT_EQ(both.candidates, after.candidates);
  }
  EXPECT_GT(filled, 20u);
  EXPECT_GT(after.relabelled, 0u);
  EXPECT_EQ(after.gapsFilled, 0u);
}

// A flagged label in two regions gets a key per region; a flagged label in
// one region, an unflagged label and region 0 keep their labels; the regions
// may be the grid downsampled.
TEST(LabelVolumes, SplitLabelsKeyEachRegionOfAFlaggedLabel) {
  GridGeometry g;
  g.dims = {8, 4, 4};
  LabelGrid grid(g, 0);
  for (std::int64_t k = 0; k < 4; ++k)
    for (std::int64_t j = 0; j < 4; ++j)
      for (std::int64_t i = 0; i < 8; ++i) grid.at(i, j, k) = j < 2 ? 5 : (i < 4 ? 6 : 7);
  GridGeometry h;
  h.dims = {4, 2, 2};
  LabelGrid regions(h, 0);
  for (std::int64_t k = 0; k < 2; ++k)
    for (std::int64_t j = 0; j < 2; ++j)
      for (std::int64_t i = 0; i < 4; ++i) regions.at(i, j, k) = i < 2 ? 1 : 2;
  regions.at(0, 0, 0) = 0;
  std::vector<std::uint8_t> flagged(8, 0);
  flagged[5] = flagged[6] = 1;
  const SplitLabels split = splitLabels(grid, flagged, regions, 2);
  ASSERT_EQ(split.labelOf.size(), 10u);
  for (Label l = 0; l < 8; ++l) EXPECT_EQ(split.labelOf[l], l);
  EXPECT_EQ(split.labelOf[8], 5);
  EXPECT_EQ(split.labelOf[9], 5);
  EXPECT_EQ(split.grid.at(0, 0, 0), 5);  // region 0
  EXPECT_EQ(split.grid.at(2, 0, 0), 8);
  EXPECT_EQ(split.grid.at(5, 1, 3), 9);
  EXPECT_EQ(split.grid.at(1, 3, 0), 6);  // one region only
  EXPECT_EQ(split.grid.at(5, 3, 0), 7);  // not flagged
  // Nothing to split: labelOf empty.
  flagged[5] = 0;
  EXPECT_TRUE(splitLabels(grid, flagged, regions, 2).labelOf.empty());
  EXPECT_THROW(splitLabels(grid, flagged, regions, 1), RuntimeFailure);
}

TEST(LabelVolumes, RejectsAGridOfAnotherGeometry) {
  const Scene& s = junctionSphere();
  const auto deformed = deformPositions(s.rest.positions, test::rotation(gridCentre(s.source.geometry()), {0, 0, 1}, 30.0));
  LabelGrid other(s.source.geometry());
  const std::vector<double> targets = deformedLabelVolumes(s.source, s.rest, deformed);
  EXPECT_THROW(preserveLabelVolumes(other, s.source, s.rest, deformed, targets), InputError);
}

}  // namespace
}  // namespace vox
