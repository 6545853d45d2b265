#pragma once
// Disjoint sets over the indices 0..n-1 (union-find with path halving), the
// one component search of the project: cage parts, surface components,
// transfer-mesh islands, label components of meshes and grids.
//
// unite() makes the smaller root the parent, so a set's representative is
// its smallest index whatever the order of the unions: results that list
// components by representative do not depend on scheduling.

#include <cstdint>
#include <numeric>
#include <vector>

namespace vox {

class DisjointSets {
public:
  explicit DisjointSets(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), std::int32_t(0)); }

  std::size_t size() const { return parent_.size(); }

  // The representative (smallest index) of x's set.
  std::int32_t find(std::int32_t x) {
    while (parent_[std::size_t(x)] != x) {
      parent_[std::size_t(x)] = parent_[std::size_t(parent_[std::size_t(x)])];
      x = parent_[std::size_t(x)];
    }
    return x;
  }

  // Joins the sets of a and b; returns false when they were one set already.
  bool unite(std::int32_t a, std::int32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return false;
    if (a < b) parent_[std::size_t(b)] = a;
    else parent_[std::size_t(a)] = b;
    return true;
  }

  // Per index, its representative.
  std::vector<std::int32_t> representatives() {
    std::vector<std::int32_t> out(parent_.size());
    for (std::size_t i = 0; i < parent_.size(); ++i) out[i] = find(std::int32_t(i));
    return out;
  }

private:
  std::vector<std::int32_t> parent_;
};

}  // namespace vox
