#include "geometry/raster/rasterize.h"

#include "geometry/raster/posed_extent.h"

#include "geometry/error.h"
#include "geometry/parallel.h"
#include "geometry/progress.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace vox {

namespace {

// Widening of a tet's source slice range, in source voxels: the GPU maps
// samples in float and may land a hair outside the tet's rest box.
constexpr double kSourceRangeMargin = 1e-3;

void requireFinite(const std::vector<Eigen::Vector3d>& positions, const std::string& what) {
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (!positions[i].allFinite()) throw InputError(what, "vertex " + std::to_string(i) + " has a non-finite coordinate");
}

// Most frequent label, ties to the lowest.
Label majorityLabel(const Label* labels, int n) {
  bool uniform = true;
  for (int i = 1; i < n && uniform; ++i) uniform = labels[i] == labels[0];
  if (uniform) return labels[0];
  Label best = 0;
  int bestCount = 0;
  for (int i = 0; i < n; ++i) {
    const Label l = labels[i];
    int count = 0;
    for (int j = 0; j < n; ++j) count += labels[j] == l;
    if (count > bestCount || (count == bestCount && l < best)) {
      best = l;
      bestCount = count;
    }
  }
  return best;
}

Label sampleLabel(std::uint32_t state) {
  return (state & kResolvedSample) && state != kNoTet ? Label(state & 0xFFFFu) : Label(0);
}

}  // namespace

GridGeometry deformedGridGeometry(const GridGeometry& source, const std::vector<Eigen::Vector3d>& deformed) {
  const PosedExtent e = posedExtent(source, deformed);
  if (!(e.voxels <= double(kMaxGridVoxels)))
    throw InputError("deformed positions", "they span " + std::to_string(std::int64_t(e.dims.x())) + " x " +
                                               std::to_string(std::int64_t(e.dims.y())) + " x " +
                                               std::to_string(std::int64_t(e.dims.z())) + " voxels, more than the largest supported grid (" +
                                               std::to_string(kMaxGridVoxels) + " voxels)");
  GridGeometry out = source;
  // Exact: posedExtent bounds every value by kMaxGridVoxels.
  for (int a = 0; a < 3; ++a) out.dims[std::size_t(a)] = std::int64_t(e.dims[a]);
  out.origin = source.origin + source.spacing.cwiseProduct(e.first);
  out.validate("deformed grid");
  return out;
}

void requireOutputGrid(const LabelGrid& posed, const GridGeometry& out) {
  if (out.dims != posed.dims() || (out.origin - posed.origin()).norm() > 1e-6 * out.spacing.norm() ||
      (out.spacing - posed.spacing()).norm() > 1e-9 * out.spacing.norm())
    throw InputError("posed grid", "its geometry is not the output grid of this deformation");
}

GridGeometry sampleLattice(const GridGeometry& output, int samples) {
  GridGeometry lattice = output;
  const double k = double(samples);
  for (int a = 0; a < 3; ++a) lattice.dims[std::size_t(a)] = output.dims[std::size_t(a)] * samples;
  lattice.spacing = output.spacing / k;
  lattice.origin = output.origin - output.spacing * ((k - 1.0) / (2.0 * k));
  return lattice;
}

RasterizationPlan::RasterizationPlan(const GridGeometry& source, const TetMesh& rest,
                                     const std::vector<Eigen::Vector3d>& deformed, int samples)
    : source_(source), samples_(samples), connectivity_(rest.tets) {
  if (samples < 1 || samples > kMaxRasterSamples)
    throw InputError("rasterization", "samples per axis must be 1.." + std::to_string(kMaxRasterSamples) + ", got " +
                                          std::to_string(samples));
  rest.validate("transfer mesh");
  if (deformed.size() != rest.positions.size())
    throw InputError("deformed positions", std::to_string(deformed.size()) + " positions for a transfer mesh of " +
                                               std::to_string(rest.positions.size()) + " vertices");
  output_ = deformedGridGeometry(source, deformed);
  lattice_ = sampleLattice(output_, samples);
  tets_ = latticeTets(lattice_, deformed, rest.tets);

  restIndex_.resize(rest.positions.size());
  for (std::size_t i = 0; i < rest.positions.size(); ++i) restIndex_[i] = latticeCoordinates(source, rest.positions[i]);
  sourceZ_.resize(connectivity_.size());
  const double nz = double(source.dims[2]);
  for (std::size_t t = 0; t < connectivity_.size(); ++t) {
    double lo = restIndex_[std::size_t(connectivity_[t][0])].z(), hi = lo;
    for (int k = 1; k < 4; ++k) {
      const double z = restIndex_[std::size_t(connectivity_[t][std::size_t(k)])].z();
      lo = std::min(lo, z);
      hi = std::max(hi, z);
    }
    const double first = std::max(std::floor(lo + 0.5 - kSourceRangeMargin), 0.0);
    const double last = std::min(std::floor(hi + 0.5 + kSourceRangeMargin), nz - 1.0);
    sourceZ_[t] = first <= last ? std::array<std::int32_t, 2>{std::int32_t(first), std::int32_t(last)}
                                : std::array<std::int32_t, 2>{0, -1};
  }
}

std::array<Eigen::Vector3d, 4> RasterizationPlan::restCorners(std::int32_t t) const {
  const Tet& tet = connectivity_[std::size_t(t)];
  return {restIndex_[std::size_t(tet[0])], restIndex_[std::size_t(tet[1])], restIndex_[std::size_t(tet[2])],
          restIndex_[std::size_t(tet[3])]};
}

TetAffineMap<3> RasterizationPlan::sourceMap(std::int32_t t) const {
  return tetAffineMap<3>(tets_[std::size_t(t)], restCorners(t));
}

SlabTets RasterizationPlan::slab(std::int64_t z0, std::int64_t z1) const {
  return slabTets(tets_, std::int32_t(z0 * samples_), std::int32_t(z1 * samples_));
}

SliceRange RasterizationPlan::sourceSlices(const SlabTets& slab) const {
  std::int64_t first = source_.dims[2], last = 0;
  for (std::int32_t t : slab.tets) {
    const auto& r = sourceZ_[std::size_t(t)];
    if (r[0] > r[1]) continue;
    first = std::min<std::int64_t>(first, r[0]);
    last = std::max<std::int64_t>(last, std::int64_t(r[1]) + 1);
  }
  return first < last ? SliceRange{first, last} : SliceRange{};
}

void resolveSamples(const RasterizationPlan& plan, const SlabTets& slab, const Label* window, std::int64_t w0,
                    std::int64_t w1, std::uint32_t* state, int threads) {
  const GridGeometry& lattice = plan.lattice();
  const GridGeometry& src = plan.source();
  const std::int64_t nx = lattice.dims[0], ny = lattice.dims[1];
  const std::int64_t sourceSlice = src.sliceVoxels();
  parallelFor((slab.z1 - slab.z0) * ny, threads, [&](std::int64_t r) {
    const std::int32_t y = std::int32_t(r % ny), z = slab.z0 + std::int32_t(r / ny);
    std::uint32_t* row = state + r * nx;
    for (std::int32_t x = 0; x < nx; ++x) {
      const std::uint32_t s = row[x];
      if (s & kResolvedSample) continue;  // resolved, or kNoTet
      const std::int32_t t = slab.tets[s];
      const Eigen::Vector4d lambda = plan.tets()[std::size_t(t)].barycentric(x, y, z);
      const auto corners = plan.restCorners(t);
      const Eigen::Vector3d p = lambda[0] * corners[0] + lambda[1] * corners[1] + lambda[2] * corners[2] + lambda[3] * corners[3];
      // Nearest source voxel centre (GridGeometry::voxelAt in index space).
      std::int64_t v[3];
      bool inside = true;
      for (int a = 0; a < 3; ++a) {
        const double c = std::floor(p[a] + 0.5);
        inside = inside && c >= 0.0 && c < double(src.dims[std::size_t(a)]);
        v[a] = inside ? std::int64_t(c) : 0;
      }
      if (!inside) {
        row[x] = kResolvedSample;
      } else if (v[2] >= w0 && v[2] < w1) {
        row[x] = kResolvedSample | window[(v[2] - w0) * sourceSlice + v[1] * src.dims[0] + v[0]];
      }
    }
  });
}

void reduceSamples(const RasterizationPlan& plan, const SlabTets& slab, const std::uint32_t* state, Label* out,
                   int threads) {
  const int k = plan.samples();
  const GridGeometry& lattice = plan.lattice();
  const std::int64_t nx = plan.output().dims[0], ny = plan.output().dims[1];
  const std::int64_t lx = lattice.dims[0], ly = lattice.dims[1];
  const std::int64_t slices = (slab.z1 - slab.z0) / k;
  parallelFor(slices * ny, threads, [&](std::int64_t r) {
    const std::int64_t j = r % ny, l = r / ny;
    Label* row = out + r * nx;
    if (k == 1) {
      const std::uint32_t* in = state + r * nx;
      for (std::int64_t i = 0; i < nx; ++i) row[i] = sampleLabel(in[i]);
      return;
    }
    Label labels[kMaxRasterSamples * kMaxRasterSamples * kMaxRasterSamples];
    for (std::int64_t i = 0; i < nx; ++i) {
      int n = 0;
      for (int c = 0; c < k; ++c)
        for (int b = 0; b < k; ++b) {
          const std::uint32_t* in = state + ((l * k + c) * ly + (j * k + b)) * lx + i * k;
          for (int a = 0; a < k; ++a) labels[n++] = sampleLabel(in[a]);
        }
      row[i] = majorityLabel(labels, n);
    }
  });
}

std::vector<SliceRange> sourceWindows(const SliceRange& needed, const SliceRange& resident, std::int64_t capacity,
                                      std::int64_t sourceSlices) {
  if (needed.empty()) return {};
  if (resident.contains(needed)) return {resident};
  capacity = std::max<std::int64_t>(1, capacity);
  if (needed.count() <= capacity) {
    const std::int64_t first = std::max<std::int64_t>(0, std::min(needed.first, sourceSlices - capacity));
    return {SliceRange{first, std::min(sourceSlices, first + capacity)}};
  }
  std::vector<SliceRange> windows;
  for (std::int64_t w = needed.first; w < needed.last; w += capacity) windows.push_back({w, std::min(needed.last, w + capacity)});
  return windows;
}

LabelGrid rasterizeAllSlabs(SlabRasterizer& engine) {
  LabelGrid out(engine.outputGeometry());
  const std::int64_t nz = out.dims()[2], step = std::max<std::int64_t>(1, engine.slabSlices());
  ProgressCounter progress("rasterize", double(nz));
  for (std::int64_t z0 = 0; z0 < nz; z0 += step) {
    const std::int64_t z1 = std::min(nz, z0 + step);
    engine.rasterizeSlab(z0, z1, out.data() + z0 * out.geometry().sliceVoxels());
    progress.advance(double(z1 - z0));
  }
  progress.finish();
  return out;
}

CpuSlabRasterizer::CpuSlabRasterizer(const RasterizationPlan& plan, GridSliceReader& source, const CpuRasterizerLimits& limits,
                                     int threads)
    : plan_(plan), source_(source), limits_(limits), threads_(threads) {}

std::int64_t CpuSlabRasterizer::slabSlices() const {
  return slabSlicesHolding(limits_.slabSamples, plan_.samplesPerOutputSlice());
}

void CpuSlabRasterizer::rasterizeSlab(std::int64_t z0, std::int64_t z1, Label* out) {
  const SlabTets slab = plan_.slab(z0, z1);
  state_.resize(std::size_t((z1 - z0) * plan_.samplesPerOutputSlice()));
  locateLatticePoints(plan_.tets(), slab, plan_.lattice(), state_.data(), threads_);
  const std::int64_t sourceSlice = plan_.source().sliceVoxels();
  const std::int64_t capacity = std::max<std::int64_t>(1, limits_.windowVoxels / sourceSlice);
  for (const SliceRange& w : sourceWindows(plan_.sourceSlices(slab), resident_, capacity, plan_.source().dims[2])) {
    if (!(w == resident_)) {
      window_.resize(std::size_t(w.count() * sourceSlice));
      source_.readSlices(w.first, w.count(), window_.data());
      resident_ = w;
    }
    resolveSamples(plan_, slab, window_.data(), w.first, w.last, state_.data(), threads_);
  }
  reduceSamples(plan_, slab, state_.data(), out, threads_);
}

LabelGrid rasterizeDeformedGrid(const LabelGrid& source, const TetMesh& rest, const std::vector<Eigen::Vector3d>& deformed,
                                const RasterizeOptions& options) {
  const RasterizationPlan plan(source.geometry(), rest, deformed, options.samples);
  LabelGrid out(plan.output());
  // Slabs of whole output slices: `samples` lattice slices each.
  const std::int64_t samples = plan.samples();
  const std::int64_t slabSlices = slabSlicesHolding(kSlabPoints, plan.samplesPerOutputSlice());
  ProgressCounter progress("rasterize", double(plan.output().dims[2]));
  forEachLocatedSlab(plan.tets(), plan.lattice(), slabSlices * samples, options.threads,
                     [&](const SlabTets& slab, std::uint32_t* state) {
                       const std::int64_t z0 = slab.z0 / samples, z1 = slab.z1 / samples;
                       resolveSamples(plan, slab, source.data(), 0, source.dims()[2], state, options.threads);
                       reduceSamples(plan, slab, state, out.data() + z0 * plan.output().sliceVoxels(), options.threads);
                       progress.advance(double(z1 - z0));
                     });
  progress.finish();
  return out;
}

}  // namespace vox
