// Per-frame update of the interactive deformation (FrameDeformer::update:
// cage ARAP -> Green coordinates to the envelope and to the transfer-mesh
// vertices inside the cage -> rigidity propagation), on the ICRP 110 adult
// male phantom.
//
// Setup (synthetic until the CGAL cage / transfer-mesh builders are wired in):
//  - cage: a closed box around the foreground's bounding box, 20 mm margin in
//    y and z, 40 mm INSIDE it on both x sides so the outer part of each arm
//    lies outside the cage and the propagation solver has work; its sides
//    split 5 x 4 x 14 (294 vertices, 584 faces);
//  - transfer mesh: six-tet decomposition of the foreground downsampled
//    6 x 6 x 2 (a voxel is kept when any of its 72 source voxels is
//    foreground): ~39 k vertices, ~192 k tets;
//  - envelope: the centres of the boundary voxels of the foreground
//    downsampled 2 x 2 x 1 (~51 k points);
//  - pose: feet fixed, head turned by up to 20 degrees about the body axis,
//    the turn oscillating from frame to frame so ARAP never sits at rest.
// Arguments: ARAP iterations per frame, and the storage precision of the
// Green coordinates (0 double, 1 float, 2 half): the two products stream the
// whole coefficient matrix every frame, so their time follows its bytes.
// Counters: per-stage milliseconds (averaged over the iterations), the
// fastest frame, sizes.

#include "geometry/deform/solve/frame_deformer.h"
#include "geometry/deform/solve/green_coordinates.h"
#include "geometry/deform/pipeline.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/deform/pose/joint_pose.h"
#include "geometry/deform/solve/sparse_cholesky.h"
#include "geometry/io/grid_io.h"
#include "geometry/voxel_tetrahedralization.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <limits>
#include <map>
#include <tuple>
#include <memory>
#include <optional>
#include <string>
#include <utility>

namespace vox {
namespace {

// Foreground of `grid` downsampled by `factor`: a coarse voxel is 1 when any
// of its source voxels is foreground. Spacing and origin follow.
LabelGrid downsampledForeground(const LabelGrid& grid, const Index3& factor) {
  GridGeometry g = grid.geometry();
  for (int a = 0; a < 3; ++a) {
    g.dims[std::size_t(a)] = (grid.dims()[std::size_t(a)] + factor[std::size_t(a)] - 1) / factor[std::size_t(a)];
    g.spacing[a] = grid.spacing()[a] * double(factor[std::size_t(a)]);
    // Centre of coarse voxel 0 = centre of its fine voxels.
    g.origin[a] = grid.origin()[a] + 0.5 * grid.spacing()[a] * double(factor[std::size_t(a)] - 1);
  }
  LabelGrid out(g, 0);
  const Index3& d = grid.dims();
  for (std::int64_t k = 0; k < d[2]; ++k)
    for (std::int64_t j = 0; j < d[1]; ++j)
      for (std::int64_t i = 0; i < d[0]; ++i)
        if (grid.at(i, j, k) != 0) out.at(i / factor[0], j / factor[1], k / factor[2]) = 1;
  return out;
}

std::vector<Eigen::Vector3d> boundaryVoxelCentres(const LabelGrid& grid) {
  std::vector<Eigen::Vector3d> out;
  const Index3& d = grid.dims();
  for (std::int64_t k = 0; k < d[2]; ++k)
    for (std::int64_t j = 0; j < d[1]; ++j)
      for (std::int64_t i = 0; i < d[0]; ++i) {
        if (grid.at(i, j, k) == 0) continue;
        const bool boundary = grid.atOr(i - 1, j, k) == 0 || grid.atOr(i + 1, j, k) == 0 || grid.atOr(i, j - 1, k) == 0 ||
                              grid.atOr(i, j + 1, k) == 0 || grid.atOr(i, j, k - 1) == 0 || grid.atOr(i, j, k + 1) == 0;
        if (boundary) out.push_back(grid.geometry().voxelCenter(i, j, k));
      }
  return out;
}

// Closed box surface around [lo, hi] with its sides split n[axis] times,
// outward counter-clockwise faces.
TriMesh boxCage(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3i& n) {
  TriMesh m;
  std::map<std::array<int, 3>, int> index;
  auto vertex = [&](std::array<int, 3> ijk) {
    auto [it, inserted] = index.try_emplace(ijk, int(m.positions.size()));
    if (inserted) {
      Eigen::Vector3d p;
      for (int a = 0; a < 3; ++a) p[a] = lo[a] + (hi[a] - lo[a]) * double(ijk[std::size_t(a)]) / double(n[a]);
      m.positions.push_back(p);
    }
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int side = 0; side < 2; ++side)
      for (int i = 0; i < n[u]; ++i)
        for (int j = 0; j < n[v]; ++j) {
          auto corner = [&](int di, int dj) {
            std::array<int, 3> ijk{};
            ijk[std::size_t(axis)] = side * n[axis];
            ijk[std::size_t(u)] = i + di;
            ijk[std::size_t(v)] = j + dj;
            return vertex(ijk);
          };
          int a = corner(0, 0), b = corner(1, 0), c = corner(1, 1), d = corner(0, 1);
          if (side == 0) std::swap(b, d);
          m.triangles.push_back({a, b, c});
          m.triangles.push_back({a, c, d});
        }
  }
  return m;
}

struct Scene {
  TriMesh cage;
  TetMesh transferMesh;
  std::vector<Eigen::Vector3d> envelope;
  Pose pose;
  PoseHandles handles;
};

const Scene& scene() {
  static const std::unique_ptr<Scene> s = [] {
    auto sc = std::make_unique<Scene>();
    const LabelGrid grid = readGrid(std::string(VOX_ASSETS_DIR) + "/icrp110_am.nii.gz");
    sc->transferMesh = tetrahedralizeVoxels(downsampledForeground(grid, {6, 6, 2}), {.includeBackground = false});
    sc->envelope = boundaryVoxelCentres(downsampledForeground(grid, {2, 2, 1}));
    Eigen::Vector3d lo = sc->transferMesh.positions[0], hi = lo;
    for (const auto& p : sc->transferMesh.positions) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    // x: 40 mm inside the foreground's extent, so the outer side of each
    // arm is outside the cage (an inset cage, as with limb separation).
    const Eigen::Vector3d margin(-40.0, 20.0, 20.0);
    sc->cage = boxCage(lo - margin, hi + margin, {5, 4, 14});
    const double height = hi.z() - lo.z();
    const Eigen::Vector3d centre = 0.5 * (lo + hi);
    Pose& pose = sc->pose;
    PoseSelection feet;
    feet.name = "feet";
    feet.boxMin = lo - Eigen::Vector3d::Constant(100.0);
    feet.boxMax = Eigen::Vector3d(hi.x() + 100.0, hi.y() + 100.0, lo.z() + 0.05 * height);
    feet.fixed = true;
    PoseSelection head;
    head.name = "head";
    head.boxMin = Eigen::Vector3d(lo.x() - 100.0, lo.y() - 100.0, hi.z() - 0.1 * height);
    head.boxMax = hi + Eigen::Vector3d::Constant(100.0);
    head.transform.axis = Eigen::Vector3d::UnitZ();
    head.transform.angleDeg = 20.0;
    head.transform.center = Eigen::Vector3d(centre.x(), centre.y(), hi.z());
    pose.selections = {feet, head};
    sc->handles = selectHandles(pose, sc->cage, "frame_bench pose");
    return sc;
  }();
  return *s;
}

void BM_FrameUpdate(benchmark::State& state) {
  const Scene& s = scene();
  const int iterations = int(state.range(0));
  const auto precision = GreenPrecision(state.range(1));
  FrameDeformer deformer;
  deformer.precompute(s.cage, s.envelope, s.transferMesh, s.handles.vertices, {.precision = precision});
  FrameTimings sum;
  double fastest = std::numeric_limits<double>::infinity();
  int frame = 0;
  for (auto _ : state) {
    const double t = 0.5 + 0.5 * std::sin(0.2 * frame++);
    deformer.update(handleTargets(s.pose, s.handles, s.cage, t), iterations);
    const FrameTimings& f = deformer.timings();
    sum.arap += f.arap;
    sum.greenEnvelope += f.greenEnvelope;
    sum.greenTransferMesh += f.greenTransferMesh;
    sum.propagation += f.propagation;
    sum.envelopeOutside += f.envelopeOutside;
    sum.total += f.total;
    fastest = std::min(fastest, f.total);
    benchmark::DoNotOptimize(deformer.transferMeshPositions().data());
  }
  const double n = double(std::max(frame, 1));
  const FrameDeformerStats& st = deformer.stats();
  state.counters["arap_ms"] = sum.arap / n;
  state.counters["gc_envelope_ms"] = sum.greenEnvelope / n;
  state.counters["propagation_ms"] = sum.propagation / n;
  state.counters["rigid_ms"] = sum.rigidBones / n;
  state.counters["gc_tm_ms"] = sum.greenTransferMesh / n;
  state.counters["envelope_outside_ms"] = sum.envelopeOutside / n;
  state.counters["total_ms"] = sum.total / n;
  // The fastest frame: what the machine does when nothing else competes for
  // its two cores and its memory bandwidth.
  state.counters["total_min_ms"] = fastest;
  state.counters["cage_vertices"] = double(s.cage.vertexCount());
  state.counters["handles"] = double(s.handles.vertices.size());
  state.counters["envelope_in"] = double(st.envelopeInside);
  state.counters["envelope_out"] = double(st.envelopeOutside);
  state.counters["tm_vertices"] = double(s.transferMesh.vertexCount());
  state.counters["tm_tets"] = double(s.transferMesh.tetCount());
  state.counters["tm_in"] = double(st.transferMeshInside);
  state.counters["tm_out"] = double(st.transferMeshOutside);
  state.counters["unknown_tets"] = double(st.propagation.unknownTetCount);
  state.counters["gc_precompute_s"] = (st.greenEnvelopeMs + st.greenTransferMeshMs) / 1000.0;
  state.counters["propagation_factor_ms"] = st.propagationFactorMs;
  const char* names[] = {"double", "float", "half"};
  state.SetLabel(std::string(names[state.range(1)]) + " coordinates, " + SparseCholesky::backendName());
}
// Args: ARAP iterations per frame, coordinate precision (GreenPrecision:
// 0 double, 1 float, 2 half).
BENCHMARK(BM_FrameUpdate)
    ->ArgsProduct({{1, 5, 10}, {1, 2}})
    ->Args({5, 0})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0)
    ->UseRealTime();

// The same update on what `voxmorph deform` builds for the adult male:
// the automatic cage (300 vertices), the envelope, the CGAL transfer mesh,
// and a pose of assets/poses applied by a fraction oscillating from frame to
// frame: the head turn (one TM vertex outside the cage) or the arm raise
// (inset cage, cut TM, thousands of vertices placed by the propagation).
// The phone-call joint pose (2) compiles against the skeleton (body parts,
// joints) as `voxmorph deform` does; its fourth argument holds the bones
// rigid (`--rigid-bones`, with the joint zones turning with the limb).
// Arguments: ARAP iterations, precision, pose (0 head, 1 arm, 2 phone call), rigid bones.
void BM_FrameUpdatePipeline(benchmark::State& state) {
  static std::map<std::tuple<int, int, int>, std::unique_ptr<DeformationPipeline>> pipelines;
  const auto precision = GreenPrecision(state.range(1));
  const int which = int(state.range(2));
  const bool arm = which == 1, phone = which == 2, rigid = state.range(3) == 1;
  std::unique_ptr<DeformationPipeline>& pipeline = pipelines[{int(precision), which, int(rigid)}];
  static const OrganTable organs = OrganTable::read(std::string(VOX_ASSETS_DIR) + "/icrp110_am_organs.dat");
  if (!pipeline) {
    const LabelGrid grid = readGrid(std::string(VOX_ASSETS_DIR) + "/icrp110_am.nii.gz");
    const std::string path = std::string(VOX_ASSETS_DIR) + (phone ? "/poses/am_phone_call_joints.json"
                                                            : arm ? "/poses/am_right_arm_raised_45.json"
                                                                  : "/poses/am_head_turned_20.json");
    PipelineOptions options;
    if (phone) {
      skeleton::JointPoseOptions joints;
      if (rigid) joints.jointZone = skeleton::JointZone::Child;
      options = skeleton::skeletalPoseOptions(readPose(path), path, grid, organs, {}, std::nullopt, joints);
      options.rigidBones = rigid;
    } else {
      options = poseOptions(readPose(path), path, arm ? std::optional<OrganTable>(organs) : std::nullopt);
    }
    options.frame.precision = precision;
    pipeline = std::make_unique<DeformationPipeline>(grid, options);
  }
  Pose pose = pipeline->pose();
  pose.arapIterations = int(state.range(0));
  pipeline->setPose(pose, "pose");
  FrameTimings sum;
  double fastest = std::numeric_limits<double>::infinity();
  int frame = 0;
  for (auto _ : state) {
    pipeline->deform(0.5 + 0.5 * std::sin(0.2 * frame++));
    const FrameTimings& f = pipeline->deformer().timings();
    sum.arap += f.arap;
    sum.greenTransferMesh += f.greenTransferMesh;
    sum.greenEnvelope += f.greenEnvelope;
    sum.propagation += f.propagation;
    sum.rigidBones += f.rigidBones;
    sum.total += f.total;
    fastest = std::min(fastest, f.total);
  }
  const double n = double(std::max(frame, 1));
  const FrameDeformerStats& st = pipeline->deformer().stats();
  state.counters["arap_ms"] = sum.arap / n;
  state.counters["gc_tm_ms"] = sum.greenTransferMesh / n;
  state.counters["gc_envelope_ms"] = sum.greenEnvelope / n;
  state.counters["propagation_ms"] = sum.propagation / n;
  state.counters["rigid_ms"] = sum.rigidBones / n;
  state.counters["total_ms"] = sum.total / n;
  state.counters["total_min_ms"] = fastest;
  state.counters["cage_vertices"] = double(pipeline->cage().vertexCount());
  state.counters["envelope_vertices"] = double(pipeline->envelope().vertexCount());
  state.counters["tm_vertices"] = double(pipeline->transferMesh().vertexCount());
  state.counters["tm_out"] = double(st.transferMeshOutside);
  const char* names[] = {"double", "float", "half"};
  state.counters["rigid_vertices"] = double(st.rigidVertices);
  state.SetLabel(std::string(phone ? (rigid ? "phone call, rigid bones, " : "phone call, ") : arm ? "arm pose, " : "head pose, ") +
                 names[state.range(1)] + " coordinates, " + SparseCholesky::backendName());
}
BENCHMARK(BM_FrameUpdatePipeline)
    ->ArgsProduct({{1, 5, 10}, {1, 2}, {0}, {0}})
    ->Args({10, 2, 1, 0})
    ->Args({10, 1, 1, 0})
    ->Args({10, 1, 2, 0})
    ->Args({10, 1, 2, 1})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0)
    ->UseRealTime();

// Computing Green coordinates (the one-time embedding), per point.
void BM_GreenCoordinatesPrecompute(benchmark::State& state) {
  const Scene& s = scene();
  const std::span<const Eigen::Vector3d> points(s.envelope.data(), std::min<std::size_t>(s.envelope.size(), 4000));
  for (auto _ : state) benchmark::DoNotOptimize(greenCoordinates(s.cage, points, GreenPrecision::Float).pointCount());
  state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(points.size()));
}
BENCHMARK(BM_GreenCoordinatesPrecompute)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace vox

BENCHMARK_MAIN();
