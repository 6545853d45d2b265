#include "geometry/remesh/hull_constraint.h"

namespace vox::remesh {

HullConstraint::HullConstraint(const RemeshComplex& complex) {
  for (std::int32_t t = 0; t < complex.tetSlots() && empty_; ++t)
    if (complex.tetAlive(t) && complex.label(t) == kDummyLabel) empty_ = false;
}

HullConstraint::Planes HullConstraint::planes(const RemeshComplex& complex, const VertexNeighborhood& vertex) const {
  Planes out;
  if (empty_ || !vertex.onHull()) return out;
  for (std::int32_t t : vertex.tets) {
    if (complex.label(t) != kDummyLabel) continue;
    const Tet& q = complex.tet(t);
    const Eigen::Vector3d* p[3];
    int n = 0;
    for (std::int32_t v : q)
      if (v != complex.dummyVertex()) p[n++] = &complex.position(v);
    std::uint8_t facet = 0;
    for (int a = 0; a < 3; ++a)
      if ((*p[0])[a] == (*p[1])[a] && (*p[0])[a] == (*p[2])[a]) {
        facet |= std::uint8_t(1u << a);
        out.at[a] = (*p[0])[a];
      }
    if (facet == 0) out.frozen = true;
    out.mask |= facet;
  }
  if (out.mask == 0) out.frozen = true;
  return out;
}

bool HullConstraint::allows(const Planes& planes, const Eigen::Vector3d& p) {
  if (planes.frozen) return false;
  for (int a = 0; a < 3; ++a)
    if ((planes.mask >> a) & 1u && p[a] != planes.at[a]) return false;
  return true;
}

Eigen::Vector3d HullConstraint::snap(const Planes& planes, const Eigen::Vector3d& p) {
  Eigen::Vector3d q = p;
  for (int a = 0; a < 3; ++a)
    if ((planes.mask >> a) & 1u) q[a] = planes.at[a];
  return q;
}

}  // namespace vox::remesh
