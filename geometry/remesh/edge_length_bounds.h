#pragma once
// Edge length thresholds of the uniform remesher (thesis 2.2.1): an edge is
// split above e_max = 4/3 l and collapsed below e_min = 4/5 l, the values
// that reduce the deviation from the target length l [Bot05].

namespace vox::remesh {

struct EdgeLengthBounds {
  double target = 0.0;  // l, mm
  double emin = 0.0;
  double emax = 0.0;

  static EdgeLengthBounds forTarget(double l) { return {l, 4.0 * l / 5.0, 4.0 * l / 3.0}; }
};

}  // namespace vox::remesh
