// voxmorph synth: synthetic label grids for tests and examples.

#include "app/command_line.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/output_path.h"
#include "geometry/synth.h"

#include <cstdio>

namespace vox::app {

void addSynthCommand(CLI::App& app) {
  struct Options {
    std::string kind, output, organs;
    int size = 96;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("synth", "Write a synthetic label grid");
  cmd->add_option("kind", o->kind, "spheres (3 nested materials) | junctions (1- and 0-junctions) | stick (arms touch the trunk) | "
                                  "skeleton (the stick with named bones: body parts and joints)")
      ->required()
      ->check(CLI::IsMember({"spheres", "junctions", "stick", "skeleton"}));
  cmd->add_option("-o,--output", o->output, "Output grid (.nii.gz, .mha, .nrrd, .inr ...)")->required();
  cmd->add_option("--size", o->size, "Voxels along the longest axis")->check(integerIn(8, 4096));
  cmd->add_option("--organs", o->organs, "Also write an organ table naming the labels");
  cmd->callback([o] {
    checkOutputPath(o->output, OutputKind::Grid, "--output");
    checkOutputPath(o->organs, OutputKind::Text, "--organs");
    const SynthKind kind = synthKindFromName(o->kind);
    const LabelGrid grid = synthesize(kind, o->size);
    writeGrid(o->output, grid);
    if (!o->organs.empty()) synthOrganTable(kind).write(o->organs);
    std::printf("%s: %s grid %lld x %lld x %lld\n", o->output.c_str(), synthKindName(kind), (long long)grid.dims()[0],
                (long long)grid.dims()[1], (long long)grid.dims()[2]);
  });
}

}  // namespace vox::app
