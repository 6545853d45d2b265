#pragma once
// Nearest-vertex queries among candidate points by a sweep over them sorted
// along x: scan outwards from the query's x until the x gap alone exceeds
// the best distance. Of candidates at equal distance, the smaller index
// wins (whatever the order of the sort).

#include <Eigen/Core>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace vox {

class NearestVertex {
public:
  // points outlives the index; candidates are indices into it.
  NearestVertex(const std::vector<Eigen::Vector3d>& points, const std::vector<std::int32_t>& candidates)
      : points_(points), order_(candidates) {
    std::sort(order_.begin(), order_.end(), [&](std::int32_t a, std::int32_t b) { return points_[std::size_t(a)].x() < points_[std::size_t(b)].x(); });
  }

  // The nearest candidate to q (-1 with none).
  std::int32_t query(const Eigen::Vector3d& q) const {
    const auto start = std::lower_bound(order_.begin(), order_.end(), q.x(),
                                        [&](std::int32_t v, double x) { return points_[std::size_t(v)].x() < x; }) -
                       order_.begin();
    double best = std::numeric_limits<double>::infinity();
    std::int32_t bestVertex = -1;
    auto visit = [&](std::ptrdiff_t k) {
      const Eigen::Vector3d& p = points_[std::size_t(order_[std::size_t(k)])];
      const double dx = p.x() - q.x();
      if (dx * dx > best) return false;
      const double d = (p - q).squaredNorm();
      if (d < best || (d == best && order_[std::size_t(k)] < bestVertex)) {
        best = d;
        bestVertex = order_[std::size_t(k)];
      }
      return true;
    };
    for (std::ptrdiff_t k = start; k < std::ptrdiff_t(order_.size()) && visit(k); ++k) {
    }
    for (std::ptrdiff_t k = start - 1; k >= 0 && visit(k); --k) {
    }
    return bestVertex;
  }

private:
  const std::vector<Eigen::Vector3d>& points_;
  std::vector<std::int32_t> order_;
};

}  // namespace vox
