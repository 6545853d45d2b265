#pragma once
// The interactive posing application (`voxmorph view`): a GLFW window with a
// Vulkan swapchain and Dear ImGui panels around the TM-guided ray casting of
// the full-resolution grid (gpu::RaycastKernel::renderTo, blitted to the
// screen; a scripted session may draw the same frames into an offscreen
// image instead, without a window). The posing state is a PoseEditor (geometry/deform/pose/pose_editor.h);
// the export runs deformGrid, the function `voxmorph deform` runs.

#include <string>
#include <vector>

namespace vox::app {

struct ViewerOptions {
  std::string grid;
  std::string organs;
  std::string pose;                      // setup pose: separations and first selections
  std::vector<std::string> separations;  // --separate, as `deform` takes them
  std::string cage;                      // a cage file instead of the automatic one (not yet: refused)
  std::string prepared;                  // voxmorph prepare's rest state of the grid ("" for none)
  std::string script;                    // scripted session (viewer_script.h)
  bool offscreen = false;                // the script's frames drawn into an offscreen image, no window
  std::string screenshotDir;
  std::string frameLog;                  // CSV of per-frame times
  int width = 1280, height = 720;
  bool vsync = true;
};

// Runs the application until its window closes or its script quits. Throws
// RuntimeFailure when no display is available for the window (one line),
// InputError for bad input.
void runViewer(const ViewerOptions& options);

}  // namespace vox::app
