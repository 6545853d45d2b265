#pragma once
// Edge length thresholds of the remesher (thesis 2.2.1): an edge is split
// above e_max = 4/3 l and collapsed below e_min = 4/5 l, the values that
// reduce the deviation from the target length l [Bot05]. Uniform: one l.
// Adaptive (2.3.7, eq. 2.2): l is the sizing field at the edge's mid-point.

#include "geometry/remesh/sizing_field.h"

#include <Eigen/Core>

namespace vox::remesh {

struct EdgeLengthBounds {
  double target = 0.0;  // l, mm (uniform; l_B when adaptive)
  double emin = 0.0;
  double emax = 0.0;
  const SizingField* sizing = nullptr;  // adaptive l; null: the uniform `target`

  static EdgeLengthBounds forTarget(double l) { return {l, 4.0 * l / 5.0, 4.0 * l / 3.0}; }
  static EdgeLengthBounds forSizing(double l, const SizingField* sizing) {
    EdgeLengthBounds b = forTarget(l);
    b.sizing = sizing;
    return b;
  }

  // e_max and e_min of the edge (a, b), squared.
  double emax2(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
    if (!sizing) return emax * emax;
    const double e = 4.0 * sizing->at(0.5 * (a + b)) / 3.0;
    return e * e;
  }
  double emin2(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const {
    if (!sizing) return emin * emin;
    const double e = 4.0 * sizing->at(0.5 * (a + b)) / 5.0;
    return e * e;
  }

  // The tests on the edge (a, b) of squared length l2: above e_max, at
  // least e_max, below e_min. With a sizing field, lengths outside the
  // field's range of thresholds are decided without sampling it (most
  // edges: the field is read only between 4/3 of its minimum and maximum).
  bool aboveEmax(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double l2) const {
    if (sizing && l2 <= square(4.0 * sizing->minimum() / 3.0)) return false;
    if (sizing && l2 > square(4.0 * sizing->maximum() / 3.0)) return true;
    return l2 > emax2(a, b);
  }
  bool reachesEmax(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double l2) const {
    if (sizing && l2 < square(4.0 * sizing->minimum() / 3.0)) return false;
    if (sizing && l2 >= square(4.0 * sizing->maximum() / 3.0)) return true;
    return l2 >= emax2(a, b);
  }
  bool belowEmin(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double l2) const {
    if (sizing && l2 < square(4.0 * sizing->minimum() / 5.0)) return true;
    if (sizing && l2 >= square(4.0 * sizing->maximum() / 5.0)) return false;
    return l2 < emin2(a, b);
  }

private:
  static double square(double x) { return x * x; }
};

}  // namespace vox::remesh
