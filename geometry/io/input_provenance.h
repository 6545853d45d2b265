#pragma once
// The provenance of a run from its input files (provenance.h): their
// digests, a grid with its detached data file.

#include "geometry/provenance.h"

#include <string>
#include <utility>
#include <vector>

namespace vox {

// Provenance of a run: the current working directory and the digests of the
// files given as (role, path); pairs with an empty path are skipped. A
// "grid" whose samples live in a separate file (.mhd + .raw, .nhdr +
// .raw.gz) adds that file as "grid data". Throws InputError naming a file
// that cannot be read.
Provenance makeProvenance(std::string commandLine, const std::vector<std::pair<std::string, std::string>>& files);

}  // namespace vox
