// Items (points, tets, faces) by the cells of a uniform grid their boxes
// overlap: sorted (cell, item) pairs. A box query visits every item whose
// box meets one of the cells the query box meets, so a query of the box
// [p - r, p + r] finds every point within r of p (and perhaps others).
// Cells are counted from `origin`; coordinates below it or beyond 2^20
// cells share the edge cells.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace vox {

class CellIndex {
 public:
  CellIndex(double cell, const Eigen::Vector3d& origin) : cell_(cell), origin_(origin) {}

  void add(std::int32_t item, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    const auto a = cellOf(lo), b = cellOf(hi);
    for (std::int64_t k = a[2]; k <= b[2]; ++k)
      for (std::int64_t j = a[1]; j <= b[1]; ++j)
        for (std::int64_t i = a[0]; i <= b[0]; ++i) pairs_.emplace_back(key(i, j, k), item);
  }
  // After the last add, before the first query.
  void finish() { std::sort(pairs_.begin(), pairs_.end()); }

  // Calls fn(item) for every item in a cell that the box [lo, hi] overlaps
  // (an item may come more than once).
  template <class Fn>
  void forEachIn(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, Fn&& fn) const {
    const auto a = cellOf(lo), b = cellOf(hi);
    for (std::int64_t k = a[2]; k <= b[2]; ++k)
      for (std::int64_t j = a[1]; j <= b[1]; ++j)
        for (std::int64_t i = a[0]; i <= b[0]; ++i) {
          const std::uint64_t c = key(i, j, k);
          auto it = std::lower_bound(pairs_.begin(), pairs_.end(), std::pair<std::uint64_t, std::int32_t>(c, std::numeric_limits<std::int32_t>::min()));
          for (; it != pairs_.end() && it->first == c; ++it) fn(it->second);
        }
  }

 private:
  std::array<std::int64_t, 3> cellOf(const Eigen::Vector3d& p) const {
    std::array<std::int64_t, 3> c{};
    for (int a = 0; a < 3; ++a) c[std::size_t(a)] = std::clamp<std::int64_t>(std::int64_t(std::floor((p[a] - origin_[a]) / cell_)), 0, (1 << 20) - 1);
    return c;
  }
  static std::uint64_t key(std::int64_t i, std::int64_t j, std::int64_t k) {
    return (std::uint64_t(k) << 40) | (std::uint64_t(j) << 20) | std::uint64_t(i);
  }
  double cell_;
  Eigen::Vector3d origin_;
  std::vector<std::pair<std::uint64_t, std::int32_t>> pairs_;
};

}  // namespace vox
