#pragma once
// The remesher's loops use the project's parallel loop (geometry/parallel.h):
// a static partition of [0, n), one range per thread, so that results go to
// per-index slots and do not depend on scheduling.

#include "geometry/parallel.h"

namespace vox::remesh {

using vox::parallelRanges;

}  // namespace vox::remesh
