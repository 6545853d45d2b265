// voxmorph mesh: a label grid to a multi-material tet mesh (M-MAd remesher
// on a conforming decomposition of the voxels), with its quality report.

#include "app/command_line.h"
#include "app/remesh_cli.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/mesh_io.h"
#include "geometry/remesh/adaptive_voxel_tetrahedralization.h"
#include "geometry/remesh/mesh_topology.h"
#include "geometry/remesh/meshing_estimate.h"
#include "geometry/remesh/sizing_field.h"

#include <chrono>
#include <cstdio>

namespace vox::app {

void addMeshCommand(CLI::App& app) {
  auto o = std::make_shared<RemeshCliOptions>();
  CLI::App* cmd = addGridSubcommand(app, "mesh", "Mesh a label grid into a multi-material tet mesh (M-MAd)", o->input);
  addRemeshOptions(*cmd, *o);
  cmd->callback([o] {
    installStderrProgress(o->quiet);
    checkRemeshArguments(*o);
    const auto t0 = std::chrono::steady_clock::now();
    checkGridFitsMemory(o->input, o->maxMemoryMb, kMeshGridMemory, "read the grid for meshing", "");
    const LabelGrid grid = readGrid(o->input);
    const Provenance provenance = commandProvenance(remeshInputs(*o, "grid"));
    checkRemeshEstimate(*o, remesh::estimateMeshing(grid, o->remesh.targetLength));
    setSizing(*o, grid.geometry().direction,
              [&](double boundary, double interior) { return remesh::interfaceSizingField(grid, boundary, interior); });
    const remesh::AdaptiveTetrahedralizationOptions decomposition =
        o->sizing ? remesh::adaptiveOptionsForSizing(grid.geometry(), o->remesh.targetLength, o->sizing->maximum())
                  : remesh::adaptiveOptionsForTarget(grid.geometry(), o->remesh.targetLength);
    const TetMesh initial = remesh::tetrahedralizeVoxelsAdaptive(grid, decomposition);
    const double setupSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    runRemesh(*o, initial, [&] { return remesh::computeGridTopology(grid); }, setupSeconds, provenance, &grid.geometry());
  });
}

}  // namespace vox::app
