// voxmorph remesh: a labeled tet mesh remeshed at a target edge length
// (M-MAd), keeping every label's topology and every junction.

#include "app/command_line.h"
#include "app/remesh_cli.h"
#include "geometry/io/mesh_io.h"
#include "geometry/remesh/mesh_topology.h"
#include "geometry/remesh/remesh_complex.h"
#include "geometry/remesh/sizing_field.h"

#include <chrono>
#include <cstdio>

namespace vox::app {

void addRemeshCommand(CLI::App& app) {
  auto o = std::make_shared<RemeshCliOptions>();
  CLI::App* cmd = app.add_subcommand("remesh", "Remesh a labeled tet mesh at a target edge length (M-MAd)");
  cmd->add_option("mesh", o->input, "Tet mesh (.mesh .vtu .msh); labels > 0 are materials, 0 an imaginary layer")
      ->required();
  addRemeshOptions(*cmd, *o);
  cmd->callback([o] {
    installStderrProgress(o->quiet);
    checkRemeshArguments(*o);
    const auto t0 = std::chrono::steady_clock::now();
    TetMesh input = readTetMesh(o->input);
    // Either orientation: tets of the other convention are turned over here,
    // so the input's volumes in the report are positive too.
    if (const std::size_t turned = orientPositively(input); turned > 0 && !o->quiet && o->report != "-")
      std::fprintf(stderr, "%s: %zu of %zu tets were negatively oriented; turned over\n", o->input.c_str(), turned, input.tetCount());
    remesh::checkNoFlatTets(input, o->input);
    const Provenance provenance = commandProvenance(remeshInputs(*o, "mesh"));
    checkRemeshEstimate(*o, remesh::estimateMeshing(input, o->remesh.targetLength));
    setSizing(*o, Eigen::Matrix3d::Identity(),
              [&](double boundary, double interior) { return remesh::interfaceSizingField(input, boundary, interior); });
    const double setupSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    runRemesh(*o, input, [&] { return remesh::computeMeshTopology(input); }, setupSeconds, provenance);
  });
}

}  // namespace vox::app
