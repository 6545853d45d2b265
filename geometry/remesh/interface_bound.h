#pragma once
// The interfaces' distance bound (the interface Hausdorff distance held
// under a bound, 0.45 l by default, as MMG3D's -hausd holds it). A collapse or a smoothing move of an
// interface vertex (or a flip of an interface edge for the valences) is
// made only when the interface facets it creates stay
// within the bound of the INPUT's interface of the same label pair, and the
// input's interface stays within the bound of them where it was within the
// bound of the facets they replace. Checked against the current surface
// instead, each step stays close and the steps add up (docs/BENCHMARKS.md,
// "Interface distance: which stage moves the interfaces").
//
// The input interfaces are the facets between two tets of different labels,
// one of them a domain tet (label > 0; the outside counts as label 0), of
// the complex when the bound is made: the grid's voxel interfaces when
// meshing a grid, the input mesh's interface facets when remeshing a mesh.
// Both one-sided distances are tested on samples, as the report measures
// them (interface_distance.h): the vertices, edge mid-points and centroids
// of the facets, against exact point-triangle distances to the other side.

#include "geometry/remesh/remesh_complex.h"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace vox::remesh {

// A facet between labels x < y: its index among the input's interfaces
// (InterfaceBound::pairIndex, -1 when the input has no x|y interface) and
// its corners. `changed`: created or moved by the operation (only those are
// tested against the input; unchanged ones still cover input samples).
struct InterfaceFacet {
  std::int32_t pair = -1;
  std::array<Eigen::Vector3d, 3> corners;
  bool changed = true;
};

class InterfaceBound {
public:
  // The interface facets of `complex` as it is now, and the bound in mm (> 0).
  InterfaceBound(const RemeshComplex& complex, double bound);

  double bound() const { return bound_; }
  std::size_t facetCount() const { return triangles_.size(); }

  // Index of the input's interface between labels x and y (any order), or
  // -1 when the input has none.
  std::int32_t pairIndex(std::int32_t x, std::int32_t y) const;

  // Whether p lies within r of the input's interface `pair` (never for -1).
  bool within(std::int32_t pair, const Eigen::Vector3d& p, double r) const;

  // Whether the facets `after` may replace `before` (the interface facets
  // an operation removes or moves, and those around its vertex afterwards):
  // every sample of a changed facet of `after` lies within the bound of the
  // input interface of its pair (a pair the input lacks never does), and
  // every input sample within the bound of `before` (same pair) stays within
  // it of `after`. Read-only: threads may call it at once.
  bool keeps(const std::vector<InterfaceFacet>& before, const std::vector<InterfaceFacet>& after) const;
  // keeps() for vertex v (its tets `tets`) moved to p.
  bool keepsMove(const RemeshComplex& complex, std::int32_t v, const std::vector<std::int32_t>& tets,
                 const Eigen::Vector3d& p) const;

private:
  struct Triangle {
    std::array<Eigen::Vector3f, 3> corners;
    std::int32_t pair;
  };
  // A uniform grid: the items of each cell (CSR).
  struct Cells {
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    double size = 1.0;
    std::array<std::int64_t, 3> dims{1, 1, 1};
    std::vector<std::int64_t> start;
    std::vector<std::int32_t> items;
    // Cells of `size` over [lo, hi], or coarser when that would make too many.
    void cover(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double size);
    std::int64_t count() const { return dims[0] * dims[1] * dims[2]; }
    std::array<std::int64_t, 3> cellOf(const Eigen::Vector3d& p) const;  // clamped to the grid
    std::int64_t index(std::int64_t i, std::int64_t j, std::int64_t k) const { return (k * dims[1] + j) * dims[0] + i; }
  };
  // The samples of one label pair in one cell (samples_[first, last)), and their box.
  struct SampleRun {
    std::int32_t pair, first, last;
    Eigen::Vector3f lo, hi;
  };
  // Calls visit(item) for the items of `pair` (pairOf(item)) in the cells
  // the box [lo, hi] meets until it returns true; returns whether it did.
  template <typename PairOf, typename Visit>
  static bool visitCells(const Cells& cells, std::int32_t pair, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                         const PairOf& pairOf, const Visit& visit);
  // The second test of keeps() for one pair.
  bool coveredSamples(std::int32_t pair, const std::vector<InterfaceFacet>& before,
                      const std::vector<InterfaceFacet>& after) const;

  double bound_;
  std::vector<std::uint64_t> pairKeys_;  // sorted (x << 32 | y), x < y as unsigned
  std::vector<Triangle> triangles_;
  Cells triangleCells_;                  // items: triangles, sorted by pair in a cell
  std::vector<Eigen::Vector3f> samples_;  // sorted by cell, then pair
  Cells sampleCells_;                    // items: runs_, sorted by pair in a cell
  std::vector<SampleRun> runs_;
};

// Squared distance from p to the triangle (a, b, c) (Ericson, Real-Time
// Collision Detection 5.1.5).
double pointTriangleDistance2(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                              const Eigen::Vector3d& c);

}  // namespace vox::remesh
