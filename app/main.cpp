// voxmorph: label grids to tetrahedral meshes, posed grids and images.
// Exit codes: 0 success, 1 failure (bad input, I/O, GPU), 2 usage error.

#include "app/command_line.h"
#include "geometry/error.h"

#include <cstdio>
#include <new>

int main(int argc, char** argv) {
  vox::app::useHugePages(argc, argv);
  CLI::App app{"voxmorph: segmented volumes to multi-material tet meshes, posed grids and images"};
  app.name("voxmorph");
  app.require_subcommand(1);
  app.set_version_flag("--version", vox::voxmorphVersionLine());
  vox::app::recordCommandLine(argc, argv);
  vox::app::addInfoCommand(app);
  vox::app::addSynthCommand(app);
  vox::app::addMeshCommand(app);
  vox::app::addRemeshCommand(app);
  vox::app::addRenderCommand(app);
  vox::app::addCageCommand(app);
  vox::app::addPrepareCommand(app);
  vox::app::addDeformCommand(app);
  vox::app::addPartsCommand(app);
  vox::app::addViewCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  } catch (const vox::UsageError& e) {
    std::fprintf(stderr, "voxmorph: error: %s\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "voxmorph: error: out of memory\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "voxmorph: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
