// Pre-processing of the deformation on the ICRP adult male: envelope, cage
// (plain and with both arms separated from the trunk), transfer mesh from B
// and from the label groups S, at the default options. Counters give the
// sizes, the cage's validity and outliers, the TM's volume change and cover.
//
//   build/release/bench/deform_mesh_bench [--benchmark_filter=...]

#include "geometry/deform/cage/cage_builder.h"
#include "geometry/deform/cage/envelope.h"
#include "geometry/skeleton/label_groups.h"
#include "geometry/deform/cage/surface_checks.h"
#include "geometry/deform/transfer_mesh.h"
#include "geometry/io/grid_io.h"
#include "geometry/organ_table.h"

#include <benchmark/benchmark.h>

#include <memory>
#include <string>

namespace {

const vox::LabelGrid& adultMale() {
  static const auto grid = std::make_unique<vox::LabelGrid>(vox::readGrid(std::string(VOX_ASSETS_DIR) + "/icrp110_am.nii.gz"));
  return *grid;
}

const vox::LabelGrid& adultMaleGroups() {
  static const auto groups = std::make_unique<vox::LabelGrid>(
      vox::labelGroupGrid(adultMale(), vox::OrganTable::read(std::string(VOX_ASSETS_DIR) + "/icrp110_am_organs.dat")));
  return *groups;
}

double foregroundVolume(const vox::LabelGrid& grid) {
  std::int64_t n = 0;
  for (const vox::Label l : grid.labels()) n += l != 0;
  return double(n) * grid.geometry().voxelVolume();
}

void BM_Envelope(benchmark::State& state) {
  const vox::LabelGrid& grid = adultMale();
  vox::TriMesh envelope;
  for (auto _ : state) envelope = vox::extractEnvelope(grid);
  const vox::SurfaceCheck c = vox::checkSurface(envelope);
  state.counters["vertices"] = double(envelope.vertexCount());
  state.counters["valid"] = c.validCage();
  state.counters["volume_change_pct"] = 100.0 * (c.volume / foregroundVolume(grid) - 1.0);
}

void reportCage(benchmark::State& state, const vox::CageResult& r) {
  state.counters["meshed_vertices"] = double(r.report.meshedVertices);
  state.counters["vertices"] = double(r.cage.vertexCount());
  state.counters["genus"] = r.report.check.genus;
  state.counters["valid"] = r.report.check.validCage();
  state.counters["eroded"] = double(r.report.erodedVoxels);
  state.counters["outside"] = double(r.report.foregroundOutside);
}

void BM_Cage(benchmark::State& state) {
  vox::CageResult r;
  for (auto _ : state) r = vox::buildCage(adultMale());
  reportCage(state, r);
}

// Both arms separated from the trunk below the shoulders (z < 1300 mm; the
// arms touch the trunk between 1270 and 1480 mm).
void BM_InsetCage(benchmark::State& state) {
  vox::CageOptions options;
  const Eigen::AlignedBox3d belowShoulders(Eigen::Vector3d::Constant(-1e4), Eigen::Vector3d(1e4, 1e4, 1300.0));
  for (const auto arm : {vox::LabelGroup::RightArm, vox::LabelGroup::LeftArm})
    options.separations.push_back({vox::Label(arm), vox::Label(vox::LabelGroup::Trunk), belowShoulders});
  const vox::LabelGrid& groups = adultMaleGroups();
  vox::CageResult r;
  for (auto _ : state) r = vox::buildCage(groups, options);
  reportCage(state, r);
}

void BM_TransferMesh(benchmark::State& state, bool fromGroups) {
  const vox::LabelGrid& grid = adultMale();
  const vox::LabelGrid groups = fromGroups ? adultMaleGroups() : vox::binaryGroupGrid(grid);
  const vox::ScalarGrid sizing = vox::defaultSizingField(grid.geometry());
  vox::TetMesh tm;
  for (auto _ : state) tm = vox::buildTransferMesh(groups, sizing);
  double volume = 0.0;
  for (const vox::Tet& t : tm.tets) volume += vox::signedVolume(tm.positions, t);
  state.counters["vertices"] = double(tm.vertexCount());
  state.counters["tets"] = double(tm.tetCount());
  state.counters["volume_change_pct"] = 100.0 * (volume / foregroundVolume(grid) - 1.0);
  state.counters["uncovered"] = double(vox::countUncoveredVoxels(tm, grid));
}

BENCHMARK(BM_Envelope)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_Cage)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_InsetCage)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_TransferMesh, binary, false)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_TransferMesh, label_groups, true)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
