// libFuzzer harness: a body-part grid (`deform --parts`, a corrected
// `voxmorph parts` output) read from arbitrary bytes as NIfTI and checked
// against the synthetic skeleton figure (userBodyParts: dims, voxel size,
// part values), as deform and render check it before the work.

#include "geometry/io/grid_io.h"
#include "geometry/organ_table.h"
#include "geometry/skeleton/body_parts.h"
#include "geometry/synth.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The figure of the seeds (tests/fuzz/make_corpus.sh: synth skeleton --size 24).
  static const vox::LabelGrid figure = vox::synthesize(vox::SynthKind::SkeletonFigure, 24);
  static const vox::OrganTable organs = vox::synthOrganTable(vox::SynthKind::SkeletonFigure);
  vox::fuzz::readAsFile(data, size, ".nii", [](const std::string& path) {
    vox::skeleton::userBodyParts(figure, organs, vox::readGrid(path), "figure", "organs", path);
  });
  return 0;
}
