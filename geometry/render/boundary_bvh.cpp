#include "geometry/render/boundary_bvh.h"

#include "geometry/error.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vox {

namespace {

struct Builder {
  std::vector<BoundaryFace>& faces;
  const std::vector<Eigen::Vector3d>& positions;
  std::vector<Eigen::Vector3d> centroids;
  std::vector<BvhNode> nodes;

  void box(std::int32_t first, std::int32_t count, Eigen::Vector3d& lo, Eigen::Vector3d& hi) const {
    lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    hi = -lo;
    for (std::int32_t f = first; f < first + count; ++f)
      for (std::int32_t v : faces[std::size_t(f)].vertices) {
        lo = lo.cwiseMin(positions[std::size_t(v)]);
        hi = hi.cwiseMax(positions[std::size_t(v)]);
      }
  }

  std::int32_t build(std::int32_t first, std::int32_t count, int depth) {
    const auto index = std::int32_t(nodes.size());
    nodes.emplace_back();
    box(first, count, nodes.back().lo, nodes.back().hi);
    if (count <= kBvhLeafFaces || depth + 1 >= kBvhMaxDepth) {
      nodes[std::size_t(index)].rightOrFirst = first;
      nodes[std::size_t(index)].count = count;
      return index;
    }
    Eigen::Vector3d clo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), chi = -clo;
    for (std::int32_t f = first; f < first + count; ++f) {
      clo = clo.cwiseMin(centroids[std::size_t(f)]);
      chi = chi.cwiseMax(centroids[std::size_t(f)]);
    }
    int axis = 0;
    (chi - clo).maxCoeff(&axis);
    const std::int32_t half = count / 2;
    // Faces and their centroids are permuted together.
    std::vector<std::int32_t> order(static_cast<std::size_t>(count));
    for (std::int32_t i = 0; i < count; ++i) order[std::size_t(i)] = first + i;
    std::nth_element(order.begin(), order.begin() + half, order.end(), [&](std::int32_t a, std::int32_t b) {
      const double ca = centroids[std::size_t(a)][axis], cb = centroids[std::size_t(b)][axis];
      return ca < cb || (ca == cb && a < b);
    });
    std::vector<BoundaryFace> f(static_cast<std::size_t>(count));
    std::vector<Eigen::Vector3d> c(static_cast<std::size_t>(count));
    for (std::int32_t i = 0; i < count; ++i) {
      f[std::size_t(i)] = faces[std::size_t(order[std::size_t(i)])];
      c[std::size_t(i)] = centroids[std::size_t(order[std::size_t(i)])];
    }
    std::copy(f.begin(), f.end(), faces.begin() + first);
    std::copy(c.begin(), c.end(), centroids.begin() + first);
    build(first, half, depth + 1);
    const std::int32_t right = build(first + half, count - half, depth + 1);
    nodes[std::size_t(index)].rightOrFirst = right;
    nodes[std::size_t(index)].count = 0;
    return index;
  }
};

}  // namespace

std::vector<BvhNode> buildBoundaryBvh(std::vector<BoundaryFace>& faces, const std::vector<Eigen::Vector3d>& positions) {
  if (faces.empty()) throw InputError("transfer mesh", "has no boundary faces");
  if (faces.size() > std::size_t(std::numeric_limits<std::int32_t>::max() / 2))
    throw InputError("transfer mesh", "has too many boundary faces");
  Builder b{faces, positions, {}, {}};
  b.centroids.reserve(faces.size());
  for (const BoundaryFace& f : faces)
    b.centroids.push_back((positions[std::size_t(f.vertices[0])] + positions[std::size_t(f.vertices[1])] +
                           positions[std::size_t(f.vertices[2])]) /
                          3.0);
  b.nodes.reserve(2 * faces.size() / kBvhLeafFaces + 2);
  b.build(0, std::int32_t(faces.size()), 0);
  return std::move(b.nodes);
}

void refitBoundaryBvh(std::vector<BvhNode>& nodes, const std::vector<BoundaryFace>& faces,
                      const std::vector<Eigen::Vector3d>& positions) {
  // Children follow their parent in depth-first order: a reverse sweep sees
  // both children of a node before the node.
  for (std::size_t i = nodes.size(); i-- > 0;) {
    BvhNode& n = nodes[i];
    if (n.count > 0) {
      n.lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
      n.hi = -n.lo;
      for (std::int32_t f = n.rightOrFirst; f < n.rightOrFirst + n.count; ++f)
        for (std::int32_t v : faces[std::size_t(f)].vertices) {
          n.lo = n.lo.cwiseMin(positions[std::size_t(v)]);
          n.hi = n.hi.cwiseMax(positions[std::size_t(v)]);
        }
    } else {
      const BvhNode& l = nodes[i + 1];
      const BvhNode& r = nodes[std::size_t(n.rightOrFirst)];
      n.lo = l.lo.cwiseMin(r.lo);
      n.hi = l.hi.cwiseMax(r.hi);
    }
  }
}

namespace {

// Slab test; returns the parameter interval of the ray inside the box.
bool rayBox(const Eigen::Vector3d& o, const Eigen::Vector3d& inv, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double& tNear,
            double& tFar) {
  tNear = -std::numeric_limits<double>::infinity();
  tFar = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    double t0 = (lo[a] - o[a]) * inv[a], t1 = (hi[a] - o[a]) * inv[a];
    if (t0 > t1) std::swap(t0, t1);
    tNear = std::max(tNear, t0);
    tFar = std::min(tFar, t1);
  }
  return tNear <= tFar;
}

// Moller-Trumbore, front faces only (det > 0 means d . n < 0).
bool rayFrontFace(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                  const Eigen::Vector3d& c, double& t) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a;
  const Eigen::Vector3d p = d.cross(e2);
  const double det = e1.dot(p);
  if (!(det > 0.0)) return false;
  const double inv = 1.0 / det;
  const Eigen::Vector3d s = o - a;
  const double u = s.dot(p) * inv;
  if (u < -kFaceHitTolerance || u > 1.0 + kFaceHitTolerance) return false;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = d.dot(q) * inv;
  if (v < -kFaceHitTolerance || u + v > 1.0 + kFaceHitTolerance) return false;
  t = e2.dot(q) * inv;
  return true;
}

}  // namespace

FaceHit firstEntryAfter(const std::vector<BvhNode>& nodes, const std::vector<BoundaryFace>& faces,
                        const std::vector<Eigen::Vector3d>& positions, const Eigen::Vector3d& origin,
                        const Eigen::Vector3d& direction, double afterT, std::int32_t afterFace) {
  FaceHit best;
  best.t = std::numeric_limits<double>::infinity();
  if (nodes.empty()) return best;
  Eigen::Vector3d inv;
  for (int a = 0; a < 3; ++a) inv[a] = 1.0 / (direction[a] != 0.0 ? direction[a] : 1e-30);
  std::int32_t stack[2 * kBvhMaxDepth];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const BvhNode& n = nodes[std::size_t(stack[--top])];
    double tn = 0.0, tf = 0.0;
    if (!rayBox(origin, inv, n.lo, n.hi, tn, tf) || tf < afterT || tn > best.t) continue;
    if (n.count > 0) {
      for (std::int32_t f = n.rightOrFirst; f < n.rightOrFirst + n.count; ++f) {
        const Tri& v = faces[std::size_t(f)].vertices;
        double t = 0.0;
        if (!rayFrontFace(origin, direction, positions[std::size_t(v[0])], positions[std::size_t(v[1])], positions[std::size_t(v[2])], t))
          continue;
        const bool after = t > afterT || (t == afterT && f > afterFace);
        const bool better = t < best.t || (t == best.t && f < best.face);
        if (after && better) {
          best.t = t;
          best.face = f;
        }
      }
    } else {
      const std::int32_t self = std::int32_t(&n - nodes.data());
      stack[top++] = n.rightOrFirst;
      stack[top++] = self + 1;
    }
  }
  return best;
}

}  // namespace vox
