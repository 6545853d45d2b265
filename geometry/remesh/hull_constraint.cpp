#include "geometry/remesh/hull_constraint.h"

#include <limits>

namespace vox::remesh {

HullConstraint::HullConstraint(const RemeshComplex& complex) {
  lo_ = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  hi_ = -lo_;
  for (std::int32_t t = 0; t < complex.tetSlots(); ++t) {
    if (!complex.tetAlive(t) || complex.label(t) != kDummyLabel) continue;
    for (std::int32_t v : complex.tet(t)) {
      if (v == complex.dummyVertex()) continue;
      lo_ = lo_.cwiseMin(complex.position(v));
      hi_ = hi_.cwiseMax(complex.position(v));
      empty_ = false;
    }
  }
}

std::uint8_t HullConstraint::planeMask(const Eigen::Vector3d& p) const {
  std::uint8_t m = 0;
  for (int a = 0; a < 3; ++a) {
    if (p[a] == lo_[a]) m |= std::uint8_t(1u << (2 * a));
    if (p[a] == hi_[a]) m |= std::uint8_t(1u << (2 * a + 1));
  }
  return m;
}

HullConstraint::Planes HullConstraint::planes(const RemeshComplex& complex, const VertexNeighborhood& vertex) const {
  Planes out;
  if (empty_ || !vertex.onHull()) return out;
  for (std::int32_t t : vertex.tets) {
    if (complex.label(t) != kDummyLabel) continue;
    std::uint8_t facet = 0xFF;
    for (std::int32_t v : complex.tet(t))
      if (v != complex.dummyVertex()) facet &= planeMask(complex.position(v));
    if (facet == 0) out.frozen = true;
    out.mask |= facet;
  }
  if (out.mask == 0) out.frozen = true;
  return out;
}

bool HullConstraint::allows(const Planes& planes, const Eigen::Vector3d& p) const {
  if (planes.frozen) return false;
  for (int a = 0; a < 3; ++a) {
    if ((planes.mask >> (2 * a)) & 1u && p[a] != lo_[a]) return false;
    if ((planes.mask >> (2 * a + 1)) & 1u && p[a] != hi_[a]) return false;
  }
  return true;
}

Eigen::Vector3d HullConstraint::snap(const Planes& planes, const Eigen::Vector3d& p) const {
  Eigen::Vector3d q = p;
  for (int a = 0; a < 3; ++a) {
    if ((planes.mask >> (2 * a)) & 1u) q[a] = lo_[a];
    if ((planes.mask >> (2 * a + 1)) & 1u) q[a] = hi_[a];
  }
  return q;
}

}  // namespace vox::remesh
