// voxmorph view: the interactive posing application (app/viewer/viewer.h).

#include "app/command_line.h"
#include "geometry/error.h"

#ifdef VOXMORPH_HAS_VIEWER
#include "app/viewer/viewer.h"
#endif

#include <memory>

namespace vox::app {

void addViewCommand(CLI::App& app) {
#ifdef VOXMORPH_HAS_VIEWER
  auto o = std::make_shared<ViewerOptions>();
  auto maxMemoryMb = std::make_shared<std::int64_t>(0);
#else
  auto o = std::make_shared<std::string>();
#endif
  CLI::App* cmd = app.add_subcommand("view", "Pose a label grid interactively: ray-cast view, cage, gizmo, live organ volumes, export");
#ifdef VOXMORPH_HAS_VIEWER
  cmd->add_option("grid", o->grid, "Label grid (.nii .nii.gz .mha .mhd .nrrd .nhdr .inr)")->required();
  cmd->add_option("--organs", o->organs, "Organ table (ID name tissue density): names, colours, masses, label groups");
  cmd->add_option("--pose", o->pose, "Pose file to start from (docs/POSES.md): its separations shape the cage and the transfer mesh");
  cmd->add_option("--separate", o->separations, "Separate two label groups, as `deform --separate` (repeatable)")->allow_extra_args(false);
  cmd->add_option("--prepared", o->prepared, "Rest state saved by voxmorph prepare (.vxprep): its skeleton, cage, envelope and transfer mesh "
                                             "instead of building them (the setup pose's separations must be among those prepared)");
  cmd->add_option("--script", o->script, "Run a scripted session (JSON list of steps; docs/VIEWER.md) and quit");
  cmd->add_flag("--offscreen", o->offscreen, "Run the script without a window or display server: frames drawn into an offscreen image "
                                            "of the window's size (same screenshots and frame log)");
  cmd->add_option("--screenshot-dir", o->screenshotDir, "Directory for the script's screenshots");
  cmd->add_option("--frame-log", o->frameLog, "Write per-frame times (deformation, ray casting, UI, present) as CSV");
  cmd->add_option("--width", o->width, "Window width")->capture_default_str()->check(CLI::Range(720, 8192));
  cmd->add_option("--height", o->height, "Window height")->capture_default_str()->check(CLI::Range(240, 8192));
  cmd->add_flag("!--no-vsync", o->vsync, "Present as fast as frames are made (for timing)");
  cmd->add_option("--max-memory", *maxMemoryMb, "Refuse a grid whose in-core work exceeds this budget (MB; default the machine's memory)")
      ->check(integerIn(64, std::int64_t(1) << 30, "MB"));
  cmd->callback([o, maxMemoryMb] {
    if (o->offscreen && o->script.empty()) throw UsageError("--offscreen", "needs a --script (an offscreen session takes no input)");
    checkGridFitsMemory(o->grid, *maxMemoryMb, kPosedMemory, "pose it interactively", "the viewer needs the whole grid in memory");
    retainFreedMemory();
    runViewer(*o);
  });
#else
  cmd->add_option("grid", *o, "Label grid");
  cmd->callback([] { throw RuntimeFailure("view: this build of voxmorph has no viewer (configure with VOXMORPH_BUILD_VIEWER=ON)"); });
#endif
}

}  // namespace vox::app
