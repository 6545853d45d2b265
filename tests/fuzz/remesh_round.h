#pragma once
// What the remesh and mesh harnesses run: one round of the remesher at
// `length`, on one thread, without the final flip-smooth cycles and the
// polish (about twice the executions of the default schedule).

#include "geometry/remesh/remesh.h"

namespace vox::fuzz {

inline remesh::RemeshOptions oneRemeshRound(double length) {
  remesh::RemeshOptions options;
  options.targetLength = length;
  options.iterations = 1;
  options.flipSmoothCycles = 0;
  options.polishAngle = 0.0;
  options.threads = 1;
  return options;
}

}  // namespace vox::fuzz
