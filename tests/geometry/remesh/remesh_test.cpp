// The remesher's acceptance properties on synthetic inputs: exact label and
// junction topology, no inverted or flat tet, determinism, sizes near the
// target, volumes kept.

#include "geometry/cancellation.h"
#include "geometry/error.h"
#include "geometry/mesh_quality.h"
#include "geometry/remesh/adaptive_voxel_tetrahedralization.h"
#include "geometry/remesh/interface_distance.h"
#include "geometry/remesh/meshing_estimate.h"
#include "geometry/remesh/mesh_topology.h"
#include "geometry/remesh/remesh.h"
#include "geometry/remesh/remesh_report.h"
#include "geometry/remesh/smooth_vertices.h"
#include "geometry/remesh/tet_shape.h"
#include "geometry/synth.h"
#include "geometry/voxel_tetrahedralization.h"

#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <thread>
#include <tuple>

namespace vox::remesh {
namespace {

struct Outcome {
  TetMesh initial;
  TetMesh output;
  MeshTopology topology;  // of the grid
  RemeshComplex complex;
};

Outcome meshGrid(const LabelGrid& grid, double lInVoxels, int threads = 2, int iterations = 6, double polishAngle = 12.0) {
  Outcome o;
  const double l = lInVoxels * grid.spacing().maxCoeff();
  o.initial = tetrahedralizeVoxelsAdaptive(grid, adaptiveOptionsForTarget(grid.geometry(), l));
  o.topology = computeGridTopology(grid);
  o.complex = RemeshComplex(o.initial);
  RemeshOptions options;
  options.targetLength = l;
  options.iterations = iterations;
  options.flipSmoothCycles = 2;
  options.threads = threads;
  options.polishAngle = polishAngle;
  remeshComplex(o.complex, options);
  o.output = o.complex.toTetMesh();
  return o;
}

void expectValidAndTopologyKept(const Outcome& o, const std::string& what) {
  EXPECT_EQ(o.complex.checkConsistency(true), "") << what;
  double minVolume = std::numeric_limits<double>::infinity();
  for (const Tet& t : o.output.tets) minVolume = std::min(minVolume, signedVolume(o.output.positions, t));
  EXPECT_GT(minVolume, 0.0) << what;
  EXPECT_EQ(test::joinLines(compareTopology(o.topology, computeMeshTopology(o.output))), "") << what;
}

TEST(Remesh, JunctionSphereKeepsLabelsJunctionsAndCorners) {
  const LabelGrid grid = synthesize(SynthKind::JunctionSphere, 24);
  const Outcome o = meshGrid(grid, 2.5);
  expectValidAndTopologyKept(o, "junction sphere");
  // The case does exercise junctions: curves and corners, including the
  // outside (label 0) in their label sets.
  ASSERT_GE(o.topology.junctionCurves.size(), 4u);
  ASSERT_GE(o.topology.junctionPoints.size(), 2u);
  bool outsideCurve = false;
  for (const auto& [set, n] : o.topology.junctionCurves) outsideCurve = outsideCurve || set.front() == 0;
  EXPECT_TRUE(outsideCurve);
  // The imaginary layer is a shell of axis-aligned cube faces around the
  // domain, not the box, and its hull is unchanged: every hull facet still
  // lies in an axis-aligned plane, and the geometric tets fill the same
  // volume as at the start.
  double before = 0.0, after = 0.0;
  for (const Tet& t : o.initial.tets) before += signedVolume(o.initial.positions, t);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (const Eigen::Vector3d& p : o.initial.positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  EXPECT_LT(before, 0.95 * (hi - lo).prod());
  std::size_t hullFacets = 0;
  for (std::int32_t t = 0; t < o.complex.tetSlots(); ++t) {
    if (!o.complex.tetAlive(t)) continue;
    if (o.complex.label(t) != kDummyLabel) {
      if (!o.complex.isDummyTet(t)) after += o.complex.volume(t);
      continue;
    }
    std::vector<Eigen::Vector3d> p;
    for (std::int32_t v : o.complex.tet(t))
      if (v != o.complex.dummyVertex()) p.push_back(o.complex.position(v));
    ASSERT_EQ(p.size(), 3u);
    bool aligned = false;
    for (int a = 0; a < 3; ++a) aligned = aligned || (p[0][a] == p[1][a] && p[0][a] == p[2][a]);
    ASSERT_TRUE(aligned) << p[0].transpose() << " | " << p[1].transpose() << " | " << p[2].transpose();
    ++hullFacets;
  }
  EXPECT_GT(hullFacets, 0u);
  EXPECT_NEAR(after, before, 1e-9 * before);
  // Coarser than the voxels: far fewer tets, decent angles.
  const TetQualitySummary q = summarizeTetQuality(o.output);
  EXPECT_LT(q.tets, summarizeTetQuality(o.initial).tets / 3);
  EXPECT_GT(q.minDihedral, 10.0);
}

TEST(Remesh, NestedShellsAndStickFigureKeepTopology) {
  expectValidAndTopologyKept(meshGrid(synthesize(SynthKind::NestedSpheres, 24), 2.5), "nested spheres");
  // Arms touching the trunk, thin humeri inside them, legs with a gap.
  expectValidAndTopologyKept(meshGrid(synthesize(SynthKind::StickFigure, 40), 2.0), "stick figure");
}

TEST(Remesh, ThinTubeTorusAndHollowShellKeepTopology) {
  // One-voxel-thin structures at a target length of three voxels: a tube
  // (1-junction-free but thinner than any tet), a torus (Euler 0) and a
  // hollow shell with a cavity (Euler 2), inside a block of label 1.
  GridGeometry g;
  g.dims = {20, 20, 20};
  LabelGrid grid(g, 0);
  for (int k = 2; k < 18; ++k)
    for (int j = 2; j < 18; ++j)
      for (int i = 2; i < 18; ++i) grid.at(i, j, k) = 1;
  for (int k = 3; k < 17; ++k) grid.at(5, 5, k) = 2;  // tube
  for (int j = 9; j < 15; ++j)
    for (int i = 3; i < 9; ++i)
      if (i == 3 || i == 8 || j == 9 || j == 14) grid.at(i, j, 10) = 3;  // torus (a square ring)
  for (int k = 9; k < 15; ++k)
    for (int j = 9; j < 15; ++j)
      for (int i = 10; i < 16; ++i)
        if (i == 10 || i == 15 || j == 9 || j == 14 || k == 9 || k == 14) grid.at(i, j, k) = 4;  // shell
  const MeshTopology t = computeGridTopology(grid);
  ASSERT_EQ(t.labels.at(3).euler, 0);
  ASSERT_EQ(t.labels.at(4).euler, 2);
  expectValidAndTopologyKept(meshGrid(grid, 3.0), "thin structures");
}

TEST(Remesh, DeterministicAndIndependentOfThreads) {
  const LabelGrid grid = synthesize(SynthKind::JunctionSphere, 20);
  const Outcome a = meshGrid(grid, 2.0, 2, 3);
  const Outcome b = meshGrid(grid, 2.0, 2, 3);
  const Outcome c = meshGrid(grid, 2.0, 1, 3);
  for (const Outcome* other : {&b, &c}) {
    ASSERT_EQ(a.output.tets, other->output.tets);
    ASSERT_EQ(a.output.labels, other->output.labels);
    ASSERT_EQ(a.output.positions.size(), other->output.positions.size());
    EXPECT_EQ(std::memcmp(a.output.positions.data(), other->output.positions.data(),
                          a.output.positions.size() * sizeof(Eigen::Vector3d)),
              0);
  }
}

// Stopped at any point of a run on two threads (split, collapse, flip, the
// scheduled moves of the smoothing, polish, insertion), the remesher throws
// OperationCancelled and leaves no worker waiting on another.
TEST(Remesh, StopsOnTwoThreadsWhereverItIsCancelled) {
  const LabelGrid grid = synthesize(SynthKind::JunctionSphere, 20);
  const auto start = std::chrono::steady_clock::now();
  meshGrid(grid, 2.0, 2, 3);
  const auto whole = std::chrono::steady_clock::now() - start;
  int stopped = 0;
  for (int k = 1; k < 16; ++k) {
    std::atomic<bool> stop{false};
    const ScopedCancellation scope(stop);
    std::thread watchdog([&] {
      std::this_thread::sleep_for(whole * k / 16);
      stop = true;
    });
    try {
      meshGrid(grid, 2.0, 2, 3);
    } catch (const OperationCancelled&) {
      ++stopped;
    }
    watchdog.join();
  }
  EXPECT_GE(stopped, 4);  // the early quarter at least, however the load varies between runs
}

double smallestDihedral(const TetMesh& m) {
  double worst = 180.0;
  for (const Tet& t : m.tets)
    worst = std::min(worst, minDihedralDegrees(m.positions[std::size_t(t[0])], m.positions[std::size_t(t[1])],
                                               m.positions[std::size_t(t[2])], m.positions[std::size_t(t[3])]));
  return worst;
}

// The polish after the last round lifts the smallest dihedral angle of a
// mesh left without it, moving inside, surface and feature vertices, with
// the topology kept and the same result on 1 and 2 threads.
TEST(Remesh, PolishLiftsTheWorstAngleAndKeepsTopology) {
  const LabelGrid grid = synthesize(SynthKind::JunctionSphere, 24);
  Outcome o = meshGrid(grid, 2.5, 2, 4, 0.0);
  const double before = smallestDihedral(o.output);
  ASSERT_LT(before, 25.0);
  const RemeshComplex unpolished = o.complex;
  const HullConstraint hull(o.complex);
  std::size_t moved[2] = {0, 0};
  std::vector<Eigen::Vector3d> positions[2];
  for (int threads : {1, 2}) {
    o.complex = unpolished;
    const InterfaceSurfaces surfaces(o.complex, 0.5 * 2.5 * grid.spacing().maxCoeff(), true);
    moved[threads - 1] = polishWorstTets(o.complex, &surfaces, hull, 25.0, threads);
    positions[threads - 1] = o.complex.positions();
  }
  EXPECT_GT(moved[0], 0u);
  EXPECT_EQ(moved[0], moved[1]);
  ASSERT_EQ(positions[0].size(), positions[1].size());
  EXPECT_EQ(std::memcmp(positions[0].data(), positions[1].data(), positions[0].size() * sizeof(Eigen::Vector3d)), 0);
  o.output = o.complex.toTetMesh();
  const double after = smallestDihedral(o.output);
  std::printf("[ stats    ] polish under 25 deg: %zu vertices moved, smallest dihedral %.2f -> %.2f deg\n", moved[0], before, after);
  EXPECT_GT(after, before + 0.5) << "before " << before;
  expectValidAndTopologyKept(o, "polished junction sphere");
  // Nothing under the angle: nothing moves.
  EXPECT_EQ(polishWorstTets(o.complex, nullptr, hull, std::min(after, before) - 0.1, 2), 0u);
}

TEST(Remesh, EdgeLengthsApproachTargetAndVolumesAreKept) {
  const LabelGrid grid = synthesize(SynthKind::NestedSpheres, 32);
  const double l = 2.5;
  const Outcome o = meshGrid(grid, l, 2, 8);
  const EdgeLengthSummary e = summarizeEdgeLengths(o.output, l);
  EXPECT_NEAR(e.meanLength, l, 0.25 * l);
  EXPECT_LT(e.meanRelativeDeviation, 0.3);
  const RemeshReport r = buildRemeshReport(o.initial, o.topology, o.output, l, {});
  EXPECT_TRUE(r.topologyDifferences.empty());
  double in = 0.0, out = 0.0;
  for (const LabelReport& lr : r.labels) {
    // The core is a ball of 4.8 voxels radius meshed with 2.5-voxel edges:
    // its inscribed polyhedron alone is some 6% smaller than the ball, and
    // the result depends on the order of the operations (-11.9% with the
    // imaginary layer filling the box, -12.7% with a shell).
    EXPECT_NEAR(lr.outputVolume / lr.inputVolume, 1.0, 0.13) << lr.label;
    in += lr.inputVolume;
    out += lr.outputVolume;
    // Interfaces stay within about a voxel of the voxel staircase.
    EXPECT_LT(lr.distance.hausdorff(), 1.5) << lr.label;
    EXPECT_GT(lr.distance.hausdorff(), 0.0) << lr.label;
  }
  EXPECT_NEAR(out / in, 1.0, 0.02);
  EXPECT_NE(reportJson(r).find("\"preserved\": true"), std::string::npos);
}

// Largest interface Hausdorff distance over the labels, in units of l.
double largestInterfaceDistance(const TetMesh& input, const TetMesh& output, double l) {
  double worst = 0.0;
  for (const auto& [label, d] : interfaceDistances(input, output)) worst = std::max(worst, d.hausdorff() / l);
  return worst;
}

// The interface bound (RemeshOptions::hausdorff): the stick figure's thin
// limbs at three voxels per edge lose their ends and corners to collapses
// without it (0.66 l from the voxel interfaces, input to output); with it
// every label stays within 0.5 l both ways, its topology kept.
TEST(Remesh, InterfacesStayWithinTheHausdorffBound) {
  const LabelGrid grid = synthesize(SynthKind::StickFigure, 40);
  const double l = 3.0 * grid.spacing().maxCoeff();
  const TetMesh initial = tetrahedralizeVoxelsAdaptive(grid, adaptiveOptionsForTarget(grid.geometry(), l));
  RemeshOptions options;
  options.targetLength = l;
  options.hausdorff = 0.0;
  const double unbounded = largestInterfaceDistance(initial, remeshTetMesh(initial, options), l);
  options.hausdorff = RemeshOptions().hausdorff;
  ASSERT_GT(options.hausdorff, 0.0);
  const TetMesh output = remeshTetMesh(initial, options);
  const double bounded = largestInterfaceDistance(initial, output, l);
  std::printf("[ stats    ] stick figure at 3 voxels: largest interface distance %.3f l without the bound, %.3f l with it\n",
              unbounded, bounded);
  EXPECT_GT(unbounded, 0.5);
  EXPECT_LE(bounded, 0.5);
  EXPECT_EQ(test::joinLines(compareTopology(computeGridTopology(grid), computeMeshTopology(output))), "");
  EXPECT_EQ(summarizeTetQuality(output).inverted, 0u);
}

TEST(Remesh, RemeshesAnExistingMeshAndRejectsABadLength) {
  // A tet mesh without an imaginary layer: the outside is then label 0 of
  // the dummy tets, with the same rules as an interface.
  const LabelGrid grid = synthesize(SynthKind::JunctionSphere, 16);
  const TetMesh input = tetrahedralizeVoxels(grid, {.includeBackground = false});
  RemeshOptions options;
  options.targetLength = 2.0;
  options.iterations = 4;
  const TetMesh output = remeshTetMesh(input, options);
  EXPECT_EQ(test::joinLines(compareTopology(computeMeshTopology(input), computeMeshTopology(output))), "");
  EXPECT_EQ(summarizeTetQuality(output).inverted, 0u);
  options.targetLength = -1.0;
  EXPECT_THROW(remeshTetMesh(input, options), InputError);
}

// At a target far above the voxels the remesher's peak is its voxel
// decomposition's, which refines to the voxels along every interface: the
// estimate counts at least its tets and their memory.
TEST(MeshingEstimate, CountsTheVoxelDecompositionAtACoarseTarget) {
  for (SynthKind kind : {SynthKind::NestedSpheres, SynthKind::JunctionSphere, SynthKind::StickFigure}) {
    const LabelGrid grid = synthesize(kind, 40);
    const double l = 16.0 * grid.spacing().maxCoeff();
    const MeshingEstimate e = estimateMeshing(grid, l);
    const TetMesh decomposition = tetrahedralizeVoxelsAdaptive(grid, adaptiveOptionsForTarget(grid.geometry(), l));
    std::int64_t domain = 0;
    for (std::int32_t label : decomposition.labels) domain += label > 0;
    EXPECT_GE(e.startTets, domain) << synthKindName(kind);
    EXPECT_LT(e.startTets, 4 * domain) << synthKindName(kind);  // not a bound so loose that it refuses good runs
    EXPECT_GT(e.startTets, e.tets) << synthKindName(kind);
    EXPECT_GE(double(e.bytes), kRemeshBytesPerDecompositionTet * double(e.startTets)) << synthKindName(kind);
    EXPECT_NE(describeEstimate(e).find("in the voxel decomposition"), std::string::npos) << describeEstimate(e);
    // A mesh remeshed coarser starts from the mesh itself.
    const MeshingEstimate m = estimateMeshing(decomposition, l);
    EXPECT_EQ(m.startTets, domain) << synthKindName(kind);
    EXPECT_GE(double(m.bytes), kRemeshBytesPerDecompositionTet * double(domain)) << synthKindName(kind);
    EXPECT_NE(describeEstimate(m).find("in the input"), std::string::npos) << describeEstimate(m);
  }
}

TEST(AdaptiveTetrahedralization, ConformingExactAndCoarser) {
  for (SynthKind kind : {SynthKind::NestedSpheres, SynthKind::JunctionSphere, SynthKind::StickFigure}) {
    const LabelGrid grid = synthesize(kind, 24);
    const TetMesh mesh = tetrahedralizeVoxelsAdaptive(grid, {.coarsestLevel = 3, .margin = 2});
    const RemeshComplex complex(mesh);  // throws unless conforming and positive
    EXPECT_EQ(complex.checkConsistency(true), "");
    EXPECT_EQ(test::joinLines(compareTopology(computeGridTopology(grid), computeMeshTopology(mesh))), "") << synthKindName(kind);
    const TetQualitySummary q = summarizeTetQuality(mesh);
    std::map<std::int32_t, double> voxels;
    std::size_t foreground = 0;
    for (Label l : grid.labels())
      if (l) {
        voxels[l] += grid.geometry().voxelVolume();
        ++foreground;
      }
    for (const auto& [label, volume] : voxels) EXPECT_NEAR(q.volumePerLabel.at(label), volume, 1e-9 * volume);
    EXPECT_LT(q.tets, 6 * foreground * 7 / 10) << synthKindName(kind);
  }
  EXPECT_THROW(tetrahedralizeVoxelsAdaptive(LabelGrid(GridGeometry{.dims = {4, 4, 4}}, 0)), InputError);
}

TEST(AdaptiveTetrahedralization, ImaginaryLayerIsAManifoldShell) {
  // Two blocks whose shells of whole cubes meet only along an edge (second
  // block beside the first diagonally in x-y) or only at a corner (in x, y
  // and z): the shell is filled in until its hull is a manifold surface.
  for (const bool corner : {false, true}) {
    GridGeometry g;
    g.dims = {24, 24, 24};
    LabelGrid grid(g, 0);
    for (std::int64_t k = 2; k < 6; ++k)
      for (std::int64_t j = 2; j < 6; ++j)
        for (std::int64_t i = 2; i < 6; ++i) {
          grid.at(i, j, k) = 1;
          grid.at(i + 14, j + 14, corner ? k + 14 : k) = 2;
        }
    const AdaptiveTetrahedralizationOptions shell{.coarsestLevel = 2, .margin = 2};
    AdaptiveTetrahedralizationOptions box = shell;
    box.shell = false;
    const TetMesh mesh = tetrahedralizeVoxelsAdaptive(grid, shell);
    const RemeshComplex complex(mesh);
    EXPECT_EQ(complex.checkConsistency(true), "");
    EXPECT_FALSE(complex.hasPinches()) << corner;
    for (std::int32_t v = 0; v < complex.vertexSlots(); ++v) ASSERT_FALSE(complex.isPinned(v)) << corner;
    EXPECT_EQ(test::joinLines(compareTopology(computeGridTopology(grid), computeMeshTopology(mesh))), "");
    // Every background voxel within the margin is meshed, and far less than the box.
    auto volumes = [](const TetMesh& m) {
      std::map<std::int32_t, double> v;
      for (std::size_t t = 0; t < m.tets.size(); ++t) v[m.labels[t]] += signedVolume(m.positions, m.tets[t]);
      return v;
    };
    const auto shellVolumes = volumes(mesh), boxVolumes = volumes(tetrahedralizeVoxelsAdaptive(grid, box));
    EXPECT_NEAR(shellVolumes.at(1), 64.0, 1e-9);
    EXPECT_NEAR(shellVolumes.at(2), 64.0, 1e-9);
    EXPECT_GE(shellVolumes.at(0), 2.0 * (8.0 * 8.0 * 8.0 - 64.0));
    EXPECT_LT(shellVolumes.at(0), 0.6 * boxVolumes.at(0)) << corner;
  }
}

}  // namespace
}  // namespace vox::remesh
