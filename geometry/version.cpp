// The version strings of provenance.h. version_string.inc is written at
// build time by cmake/git_version.cmake (VOX_PROJECT_VERSION,
// VOX_GIT_DESCRIBE) and rewritten only when it changes.

#include "geometry/provenance.h"

#include "version_string.inc"

namespace vox {

std::string voxmorphVersion() { return VOX_PROJECT_VERSION; }
std::string voxmorphGitDescribe() { return VOX_GIT_DESCRIBE; }

}  // namespace vox
