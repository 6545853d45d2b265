// Formats not implemented yet: each entry throws. Entries are removed as the
// readers and writers land; this file must be empty of entries (and deleted)
// before a release.
#include "geometry/error.h"
#include "geometry/io/mesh_io.h"

namespace vox {

namespace {
[[noreturn]] void pending(const std::string& path) { throw RuntimeFailure(path + ": format not supported yet"); }
}  // namespace

// mesh formats
TetMesh readMedit(const std::string& path) { pending(path); }
void writeMedit(const std::string& path, const TetMesh&) { pending(path); }
TetMesh readVtu(const std::string& path) { pending(path); }
void writeVtu(const std::string& path, const TetMesh&) { pending(path); }
TetMesh readGmsh(const std::string& path) { pending(path); }
void writeGmsh(const std::string& path, const TetMesh&) { pending(path); }
TriMesh readSurface(const std::string& path) { pending(path); }
void writeSurface(const std::string& path, const TriMesh&) { pending(path); }

}  // namespace vox
