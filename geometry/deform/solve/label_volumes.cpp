#include "geometry/deform/solve/label_volumes.h"

#include "geometry/raster/lattice_tets.h"
#include "geometry/raster/rasterize.h"
#include "geometry/disjoint_sets.h"
#include "geometry/error.h"
#include "geometry/parallel.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <string>

namespace vox {

namespace {

// Slices per located slab of `lattice`: half the default slab, since the
// correction keeps its candidate moves beside the point states.
std::int64_t slabSlicesFor(const GridGeometry& lattice) { return slabSlicesHolding(kSlabPoints / 2, lattice.sliceVoxels()); }

struct Move {
  std::int64_t voxel;
  float cost;  // w_from - w_to
  Label from, to;
};

// Labels and trilinear weights of the 8 source voxels around continuous index p
// (voxels off the grid count as label 0), merged per label.
int stencilLabels(const LabelGrid& source, const Eigen::Vector3d& p, std::array<Label, 8>& labels,
                  std::array<float, 8>& weights) {
  const Eigen::Vector3d base = p.array().floor();
  const Eigen::Vector3d f = p - base;
  const std::int64_t i0 = std::int64_t(base.x()), j0 = std::int64_t(base.y()), k0 = std::int64_t(base.z());
  int n = 0;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const double w = (dx ? f.x() : 1.0 - f.x()) * (dy ? f.y() : 1.0 - f.y()) * (dz ? f.z() : 1.0 - f.z());
    const Label l = source.atOr(i0 + dx, j0 + dy, k0 + dz);
    int m = 0;
    while (m < n && labels[std::size_t(m)] != l) ++m;
    if (m == n) {
      labels[std::size_t(n)] = l;
      weights[std::size_t(n)] = 0.0f;
      ++n;
    }
    weights[std::size_t(m)] += float(w);
  }
  return n;
}

double worstPercent(std::span<const std::int64_t> counts, std::span<const double> targets) {
  double worst = 0.0;
  for (std::size_t l = 1; l < targets.size(); ++l)
    if (targets[l] >= 0.5) worst = std::max(worst, 100.0 * std::abs(double(counts[l]) / targets[l] - 1.0));
  return worst;
}

// The background of `posed` that background does not connect to G''s
// border (6-connected), found over the rows' runs of background: each run
// joins the runs it overlaps in the row before (y - 1) and the slice
// before (z - 1). Returns, in voxel order, the voxels flagged in `open`
// that lie in such enclosed runs.
std::vector<std::int64_t> enclosedVoxels(const LabelGrid& posed, std::span<const std::uint8_t> open) {
  const std::int64_t nx = posed.dims()[0], ny = posed.dims()[1], nz = posed.dims()[2];
  const Label* labels = posed.data();
  struct Run {
    std::int32_t x0, x1;  // [x0, x1)
  };
  std::vector<Run> runs;
  std::vector<std::int64_t> rowStart(std::size_t(ny * nz) + 1, 0);
  for (std::int64_t r = 0; r < ny * nz; ++r) {
    const Label* row = labels + r * nx;
    for (std::int64_t x = 0; x < nx;) {
      if (row[x] != 0) {
        ++x;
        continue;
      }
      const std::int64_t x0 = x;
      while (x < nx && row[x] == 0) ++x;
      runs.push_back({std::int32_t(x0), std::int32_t(x)});
    }
    rowStart[std::size_t(r) + 1] = std::int64_t(runs.size());
  }
  DisjointSets sets(runs.size());
  // Joins the runs of rows a and b that share an x.
  const auto join = [&](std::int64_t a, std::int64_t b) {
    std::int64_t i = rowStart[std::size_t(a)], j = rowStart[std::size_t(b)];
    const std::int64_t iEnd = rowStart[std::size_t(a) + 1], jEnd = rowStart[std::size_t(b) + 1];
    while (i < iEnd && j < jEnd) {
      const Run& u = runs[std::size_t(i)];
      const Run& w = runs[std::size_t(j)];
      if (u.x0 < w.x1 && w.x0 < u.x1) sets.unite(std::int32_t(i), std::int32_t(j));
      if (u.x1 < w.x1) ++i;
      else ++j;
    }
  };
  for (std::int64_t z = 0; z < nz; ++z)
    for (std::int64_t y = 0; y < ny; ++y) {
      const std::int64_t r = z * ny + y;
      if (y > 0) join(r, r - 1);
      if (z > 0) join(r, r - ny);
    }
  std::vector<std::uint8_t> border(runs.size(), 0);
  for (std::int64_t z = 0; z < nz; ++z)
    for (std::int64_t y = 0; y < ny; ++y) {
      const std::int64_t r = z * ny + y;
      const bool edgeRow = y == 0 || z == 0 || y == ny - 1 || z == nz - 1;
      for (std::int64_t i = rowStart[std::size_t(r)]; i < rowStart[std::size_t(r) + 1]; ++i)
        if (edgeRow || runs[std::size_t(i)].x0 == 0 || runs[std::size_t(i)].x1 == nx) border[std::size_t(sets.find(std::int32_t(i)))] = 1;
    }
  std::vector<std::int64_t> enclosed;
  for (std::int64_t r = 0; r < ny * nz; ++r)
    for (std::int64_t i = rowStart[std::size_t(r)]; i < rowStart[std::size_t(r) + 1]; ++i) {
      if (border[std::size_t(sets.find(std::int32_t(i)))]) continue;
      for (std::int64_t x = runs[std::size_t(i)].x0; x < runs[std::size_t(i)].x1; ++x)
        if (open[std::size_t(r * nx + x)]) enclosed.push_back(r * nx + x);
    }
  return enclosed;
}

// Fills the enclosed voxels flagged in `open` (fillEnclosedGaps).
std::uint64_t fillGaps(LabelGrid& posed, std::span<const std::uint8_t> open, std::span<const std::uint8_t> behind) {
  const auto isBehind = [&behind](Label l) { return std::size_t(l) < behind.size() && behind[l] != 0; };
  const std::int64_t nx = posed.dims()[0], ny = posed.dims()[1], nz = posed.dims()[2], slice = nx * ny;
  Label* labels = posed.data();
  const std::array<std::int64_t, 6> step = {1, -1, nx, -nx, slice, -slice};
  const auto neighbour = [&](std::int64_t v, int n, std::int64_t& w) {
    const std::int64_t i = v % nx, j = (v / nx) % ny, k = v / slice;
    if ((n == 0 && i + 1 >= nx) || (n == 1 && i == 0) || (n == 2 && j + 1 >= ny) || (n == 3 && j == 0) || (n == 4 && k + 1 >= nz) ||
        (n == 5 && k == 0))
      return false;
    w = v + step[std::size_t(n)];
    return true;
  };
  std::vector<std::int64_t> gaps = enclosedVoxels(posed, open);
  // From the rim inward: each round labels the gap voxels beside a label by
  // the labels before the round; the bones' labels only once the others
  // reach no further.
  std::uint64_t filled = 0;
  bool withBehind = false;
  std::vector<std::pair<std::int64_t, Label>> round;
  std::vector<std::int64_t> left;
  while (!gaps.empty()) {
    round.clear();
    left.clear();
    for (const std::int64_t v : gaps) {
      std::array<Label, 6> seen{};
      std::array<int, 6> count{};
      int kinds = 0;
      std::int64_t w = 0;
      for (int n = 0; n < 6; ++n) {
        if (!neighbour(v, n, w) || labels[w] == 0 || (!withBehind && isBehind(labels[w]))) continue;
        int m = 0;
        while (m < kinds && seen[std::size_t(m)] != labels[w]) ++m;
        if (m == kinds) seen[std::size_t(kinds++)] = labels[w];
        ++count[std::size_t(m)];
      }
      if (kinds == 0) {
        left.push_back(v);
        continue;
      }
      int best = 0;
      for (int m = 1; m < kinds; ++m)
        if (count[std::size_t(m)] > count[std::size_t(best)] ||
            (count[std::size_t(m)] == count[std::size_t(best)] && seen[std::size_t(m)] < seen[std::size_t(best)]))
          best = m;
      round.push_back({v, seen[std::size_t(best)]});
    }
    if (round.empty()) {
      if (withBehind) break;  // enclosed by covered background only
      withBehind = true;
      continue;
    }
    for (const auto& [v, l] : round) labels[v] = l;
    filled += round.size();
    gaps.swap(left);
  }
  return filled;
}

}  // namespace

SplitLabels splitLabels(const LabelGrid& grid, std::span<const std::uint8_t> split, const LabelGrid& regions, int factor) {
  const auto f = std::int64_t(std::max(factor, 1));
  for (int a = 0; a < 3; ++a)
    if (regions.dims()[std::size_t(a)] != (grid.dims()[std::size_t(a)] + f - 1) / f)
      throw RuntimeFailure("splitLabels: the regions' grid is not the grid downsampled by " + std::to_string(f));
  const auto labels = std::size_t(grid.maxLabel()) + 1, kinds = std::size_t(regions.maxLabel()) + 1;
  if (labels * kinds > (std::size_t(1) << 24)) return {};
  const std::int64_t nx = grid.dims()[0], ny = grid.dims()[1], nz = grid.dims()[2];
  const auto regionOf = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return regions.at(i / f, j / f, k / f); };
  const auto flagged = [&](Label l) { return l != 0 && l < split.size() && split[l]; };
  // Which (label, region) pairs occur, slab by slab.
  std::vector<std::uint8_t> seen(labels * kinds, 0);
  std::mutex lock;
  parallelRanges(nz, workerThreads(0), [&](std::int64_t k0, std::int64_t k1) {
    std::vector<std::uint8_t> mine(labels * kinds, 0);
    for (std::int64_t k = k0; k < k1; ++k)
      for (std::int64_t j = 0; j < ny; ++j)
        for (std::int64_t i = 0; i < nx; ++i) {
          const Label l = grid.at(i, j, k);
          if (flagged(l)) mine[std::size_t(l) * kinds + regionOf(i, j, k)] = 1;
        }
    const std::lock_guard<std::mutex> hold(lock);
    for (std::size_t x = 0; x < seen.size(); ++x) seen[x] |= mine[x];
  }, 8);
  SplitLabels out;
  std::vector<Label> keyOf(labels * kinds, 0);
  std::vector<Label> labelOf(labels);
  for (std::size_t l = 0; l < labels; ++l) labelOf[l] = Label(l);
  for (std::size_t l = 0; l < labels; ++l) {
    std::size_t count = 0;
    for (std::size_t r = 1; r < kinds; ++r) count += seen[l * kinds + r];
    if (count < 2) continue;
    for (std::size_t r = 1; r < kinds; ++r) {
      if (!seen[l * kinds + r]) continue;
      if (labelOf.size() > std::size_t(std::numeric_limits<Label>::max())) return {};
      keyOf[l * kinds + r] = Label(labelOf.size());
      labelOf.push_back(Label(l));
    }
  }
  if (labelOf.size() == labels) return {};
  out.grid = grid;
  std::vector<Label>& keyed = out.grid.labels();
  parallelRanges(nz, workerThreads(0), [&](std::int64_t k0, std::int64_t k1) {
    for (std::int64_t k = k0; k < k1; ++k)
      for (std::int64_t j = 0; j < ny; ++j)
        for (std::int64_t i = 0; i < nx; ++i) {
          Label& l = keyed[std::size_t(grid.geometry().index(i, j, k))];
          if (!flagged(l)) continue;
          const Label key = keyOf[std::size_t(l) * kinds + regionOf(i, j, k)];
          if (key != 0) l = key;
        }
  }, 8);
  out.labelOf = std::move(labelOf);
  return out;
}

std::vector<double> deformedLabelVolumes(const LabelGrid& source, const TetMesh& rest,
                                         const std::vector<Eigen::Vector3d>& deformed, int threads) {
  rest.validate("transfer mesh");
  if (deformed.size() != rest.positions.size())
    throw InputError("deformed positions", std::to_string(deformed.size()) + " positions for a transfer mesh of " +
                                               std::to_string(rest.positions.size()) + " vertices");
  std::vector<double> jacobian(rest.tets.size(), 0.0);
  for (std::size_t t = 0; t < rest.tets.size(); ++t) {
    const double v0 = signedVolume(rest.positions, rest.tets[t]);
    if (v0 > 0.0) jacobian[t] = signedVolume(deformed, rest.tets[t]) / v0;
  }
  const GridGeometry& lattice = source.geometry();
  const std::vector<LatticeTet> tets = latticeTets(lattice, rest.positions, rest.tets);
  std::vector<double> volumes(std::size_t(source.maxLabel()) + 1, 0.0);
  const std::int64_t slice = lattice.sliceVoxels();
  forEachLocatedSlab(tets, lattice, slabSlicesFor(lattice), threads, [&](const SlabTets& slab, const std::uint32_t* state) {
    const Label* labels = source.data() + slab.z0 * slice;
    const std::int64_t points = (slab.z1 - slab.z0) * slice;
    for (std::int64_t i = 0; i < points; ++i)
      if (state[i] != kNoTet) volumes[labels[i]] += jacobian[std::size_t(slab.tets[state[i]])];
  });
  return volumes;
}

TetLabelVoxels tetLabelVoxels(const LabelGrid& source, const TetMesh& rest, int threads) {
  rest.validate("transfer mesh");
  const GridGeometry& lattice = source.geometry();
  const std::vector<LatticeTet> tets = latticeTets(lattice, rest.positions, rest.tets);
  // (tet, label) keys of every located voxel, slab by slab, then counted.
  std::vector<std::uint64_t> keys;
  const std::int64_t slice = lattice.sliceVoxels();
  forEachLocatedSlab(tets, lattice, slabSlicesFor(lattice), threads, [&](const SlabTets& slab, const std::uint32_t* state) {
    const Label* labels = source.data() + slab.z0 * slice;
    const std::int64_t points = (slab.z1 - slab.z0) * slice;
    for (std::int64_t i = 0; i < points; ++i)
      if (state[i] != kNoTet) keys.push_back((std::uint64_t(slab.tets[state[i]]) << 16) | labels[i]);
  });
  std::sort(keys.begin(), keys.end());
  TetLabelVoxels out;
  out.start.assign(rest.tets.size() + 1, 0);
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    const std::size_t t = std::size_t(keys[i] >> 16);
    const Label l = Label(keys[i] & 0xFFFF);
    out.labels.push_back(l);
    out.counts.push_back(std::uint32_t(j - i));
    ++out.start[t + 1];
    out.maxLabel = std::max(out.maxLabel, l);
    i = j;
  }
  for (std::size_t t = 0; t < rest.tets.size(); ++t) out.start[t + 1] += out.start[t];
  out.maxLabel = std::max(out.maxLabel, source.maxLabel());
  return out;
}

std::vector<double> deformedLabelVolumes(const TetLabelVoxels& voxels, const TetMesh& rest,
                                         const std::vector<Eigen::Vector3d>& deformed) {
  if (deformed.size() != rest.positions.size() || voxels.start.size() != rest.tets.size() + 1)
    throw InputError("deformed positions", "they do not belong to the transfer mesh the voxels were counted in");
  std::vector<double> volumes(std::size_t(voxels.maxLabel) + 1, 0.0);
  for (std::size_t t = 0; t < rest.tets.size(); ++t) {
    if (voxels.start[t] == voxels.start[t + 1]) continue;
    const double v0 = signedVolume(rest.positions, rest.tets[t]);
    if (!(v0 > 0.0)) continue;
    const double jacobian = signedVolume(deformed, rest.tets[t]) / v0;
    for (std::int64_t k = voxels.start[t]; k < voxels.start[t + 1]; ++k)
      volumes[voxels.labels[std::size_t(k)]] += jacobian * double(voxels.counts[std::size_t(k)]);
  }
  return volumes;
}

std::uint64_t fillEnclosedGaps(LabelGrid& posed, const LabelGrid& source, const TetMesh& rest, const std::vector<Eigen::Vector3d>& deformed,
                               int threads, std::span<const std::uint8_t> behind) {
  const RasterizationPlan plan(source.geometry(), rest, deformed, 1);
  const GridGeometry& out = plan.output();
  requireOutputGrid(posed, out);
  const std::int64_t slice = out.sliceVoxels();
  const Label* labels = posed.data();
  std::vector<std::uint8_t> open(std::size_t(out.voxelCount()), 0);
  forEachLocatedSlab(plan.tets(), plan.lattice(), slabSlicesFor(out), threads, [&](const SlabTets& slab, const std::uint32_t* state) {
    const std::int64_t first = std::int64_t(slab.z0) * slice, points = std::int64_t(slab.z1 - slab.z0) * slice;
    for (std::int64_t i = 0; i < points; ++i) open[std::size_t(first + i)] = state[i] == kNoTet && labels[first + i] == 0;
  });
  return fillGaps(posed, open, behind);
}

LabelVolumeCorrection preserveLabelVolumes(LabelGrid& posed, const LabelGrid& source, const TetMesh& rest,
                                           const std::vector<Eigen::Vector3d>& deformed, std::span<const double> targets,
                                           int threads, bool fillGapsFirst, std::span<const std::uint8_t> behind) {
  const RasterizationPlan plan(source.geometry(), rest, deformed, 1);
  const GridGeometry& out = plan.output();
  requireOutputGrid(posed, out);

  // Still tets (every vertex within kStillFraction of a voxel of its rest
  // position): their voxels are not candidates.
  const double stillMm = kStillFraction * source.spacing().minCoeff();
  std::vector<std::uint8_t> still(rest.tetCount(), 1);
  for (std::size_t t = 0; t < rest.tetCount(); ++t)
    for (const std::int32_t v : rest.tets[t])
      if ((deformed[std::size_t(v)] - rest.positions[std::size_t(v)]).norm() >= stillMm) still[t] = 0;
  std::vector<std::uint64_t> rowStill;
  std::uint64_t stillVoxels = 0;
  // Candidate moves, per output row so that the order is independent of the threads.
  // (The plan samples once per voxel: its lattice is the output grid.)
  const std::int64_t nx = out.dims[0], ny = out.dims[1];
  std::vector<Move> moves;
  std::uint64_t candidates = 0;
  std::vector<std::vector<Move>> rowMoves;
  std::vector<std::uint64_t> rowCandidates;
  // With fillGapsFirst, the background no tet covers (fillEnclosedGaps),
  // from the same located lattice: the fill changes no covered voxel, so
  // the moves are those after it.
  std::vector<std::uint8_t> open(fillGapsFirst ? std::size_t(out.voxelCount()) : 0, 0);
  forEachLocatedSlab(plan.tets(), plan.lattice(), slabSlicesFor(out), threads, [&](const SlabTets& slab, const std::uint32_t* state) {
    const std::int64_t z0 = slab.z0, z1 = slab.z1;
    rowMoves.assign(std::size_t((z1 - z0) * ny), {});
    rowCandidates.assign(std::size_t((z1 - z0) * ny), 0);
    rowStill.assign(std::size_t((z1 - z0) * ny), 0);
    parallelFor((z1 - z0) * ny, threads, [&](std::int64_t r) {
      const std::int32_t y = std::int32_t(r % ny), z = std::int32_t(z0 + r / ny);
      std::vector<Move>& row = rowMoves[std::size_t(r)];
      std::array<Label, 8> labels;
      std::array<float, 8> weights;
      for (std::int32_t x = 0; x < nx; ++x) {
        const std::uint32_t s = state[r * nx + x];
        const std::int64_t voxel = out.index(x, y, z);
        if (s == kNoTet) {
          if (fillGapsFirst) open[std::size_t(voxel)] = posed.data()[voxel] == 0;
          continue;
        }
        const std::int32_t t = slab.tets[s];
        const Eigen::Vector4d lambda = plan.tets()[std::size_t(t)].barycentric(x, y, z);
        const auto c = plan.restCorners(t);
        const Eigen::Vector3d p = lambda[0] * c[0] + lambda[1] * c[1] + lambda[2] * c[2] + lambda[3] * c[3];
        const int n = stencilLabels(source, p, labels, weights);
        const Label a = posed.data()[voxel];
        if (n == 1 && labels[0] == a) continue;
        if (still[std::size_t(t)]) {
          ++rowStill[std::size_t(r)];
          continue;
        }
        float wa = 0.0f;
        for (int m = 0; m < n; ++m)
          if (labels[std::size_t(m)] == a) wa = weights[std::size_t(m)];
        for (int m = 0; m < n; ++m)
          if (labels[std::size_t(m)] != a && weights[std::size_t(m)] > 0.0f)
            row.push_back({voxel, wa - weights[std::size_t(m)], a, labels[std::size_t(m)]});
        ++rowCandidates[std::size_t(r)];
      }
    });
    for (std::size_t r = 0; r < rowMoves.size(); ++r) {
      moves.insert(moves.end(), rowMoves[r].begin(), rowMoves[r].end());
      candidates += rowCandidates[r];
      stillVoxels += rowStill[r];
    }
  });
  const std::uint64_t gapsFilled = fillGapsFirst ? fillGaps(posed, open, behind) : 0;
  std::sort(moves.begin(), moves.end(), [](const Move& a, const Move& b) {
    if (a.cost != b.cost) return a.cost < b.cost;
    if (a.voxel != b.voxel) return a.voxel < b.voxel;
    return a.to < b.to;
  });

  // Counts and targets over every label either side holds; label 0 takes the rest of G'.
  Label maxLabel = posed.maxLabel();
  for (const Move& m : moves) maxLabel = std::max(maxLabel, m.to);
  const std::size_t labelCount = std::max<std::size_t>(std::size_t(maxLabel) + 1, targets.size());
  std::vector<std::int64_t> counts(labelCount, 0);
  for (const Label l : posed.labels()) ++counts[l];
  std::vector<double> goal(labelCount, 0.0);
  double foreground = 0.0;
  for (std::size_t l = 1; l < targets.size(); ++l) {
    goal[l] = targets[l];
    foreground += targets[l];
  }
  goal[0] = double(posed.voxelCount()) - foreground;
  auto deviation = [&] {
    double d = 0.0;
    for (std::size_t l = 0; l < labelCount; ++l) d += std::abs(double(counts[l]) - goal[l]);
    return d;
  };

  // Each label's deviation counts relative to its volume, so that a voxel
  // moves from a large label on target to a small one short of it.
  std::vector<double> scale(labelCount);
  for (std::size_t l = 0; l < labelCount; ++l) scale[l] = 1.0 / std::max(goal[l], 1.0);

  LabelVolumeCorrection result;
  result.candidates = candidates;
  result.still = stillVoxels;
  result.gapsFilled = gapsFilled;
  result.deviationBefore = deviation();
  result.worstPercentBefore = worstPercent(counts, goal);
  Label* labels = posed.data();
  for (bool changed = true; changed && result.sweeps < 64;) {
    changed = false;
    ++result.sweeps;
    for (const Move& m : moves) {
      if (labels[m.voxel] != m.from) continue;
      const double cf = double(counts[m.from]) - goal[m.from], ct = double(counts[m.to]) - goal[m.to];
      const double gain = (std::abs(cf) - std::abs(cf - 1.0)) * scale[m.from] + (std::abs(ct) - std::abs(ct + 1.0)) * scale[m.to];
      if (!(gain > 1e-9 * (scale[m.from] + scale[m.to]))) continue;
      labels[m.voxel] = m.to;
      --counts[m.from];
      ++counts[m.to];
      ++result.relabelled;
      changed = true;
    }
  }
  result.deviationAfter = deviation();
  result.worstPercentAfter = worstPercent(counts, goal);
  return result;
}

}  // namespace vox
