#pragma once
// Barycentric rasterization of the deformed grid (thesis 3.2.4 and 4.2.3):
// the CPU reference, used by `voxmorph deform --cpu`, by the out-of-core
// driver, and as the reference of the GPU kernel (gpu/kernels/rasterize.h).
//
// Output grid G': the source spacing and orientation, voxel centres on the
// source lattice (origin' = origin + spacing .* integer offset), covering the
// voxel centres inside the bounding box of the deformed TM vertices. For each
// output voxel centre p': the lowest-index deformed tet whose closed
// barycentric test p' passes (lattice_tets.h: watertight, ties to the lowest
// index) gives lambda; p = sum_k lambda_k v_k over the tet's rest vertices;
// the label is that of the source voxel whose centre is nearest p
// (GridGeometry::voxelAt); no containing tet, or p off the source grid, gives 0.
//
// Supersampling (`samples` = k > 1): each output voxel takes k^3 sample points
// at offsets ((s + 1/2) / k - 1/2) voxel, s = 0..k-1 per axis, each labelled
// as above; the voxel gets the most frequent label, ties going to the lowest
// label (so odd k, where ties are rarer, is the better choice).
//
// Work is done in slabs of output slices, in three stages that the GPU kernel
// mirrors: locate (lattice_tets.h: sample -> tet), resolve (tet -> source
// voxel -> label, for the source slices held in memory) and reduce (samples
// -> voxel label).

#include "geometry/raster/lattice_tets.h"
#include "geometry/grid_slices.h"
#include "geometry/label_grid.h"
#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace vox {

inline constexpr int kMaxRasterSamples = 4;

struct RasterizeOptions {
  int samples = 1;  // k: k^3 sample points per output voxel, 1..kMaxRasterSamples
  int threads = 0;  // CPU threads; 0 = every hardware thread
};

// The output grid G' for deformed TM vertex positions (grid frame, mm).
// Throws InputError("deformed positions", ...) when empty or not finite.
GridGeometry deformedGridGeometry(const GridGeometry& source, const std::vector<Eigen::Vector3d>& deformed);

// What post-processes G' in place (the volume correction, the skin cover)
// checks first: throws InputError("posed grid", ...) unless `posed` lies on
// `out`, the output grid of the deformation that made it.
void requireOutputGrid(const LabelGrid& posed, const GridGeometry& out);

// The lattice of the k^3 sample points of every output voxel: k times finer,
// sample (a,b,c) of voxel (i,j,l) is lattice point (k i + a, k j + b, k l + c).
GridGeometry sampleLattice(const GridGeometry& output, int samples);

// Whole source slices [first, last).
struct SliceRange {
  std::int64_t first = 0;
  std::int64_t last = 0;
  std::int64_t count() const { return last - first; }
  bool empty() const { return last <= first; }
  bool contains(const SliceRange& r) const { return r.empty() || (first <= r.first && r.last <= last); }
  bool operator==(const SliceRange&) const = default;
};

// Sample states after the resolve stage: kNoTet (label 0), a slab-local tet
// index (label still pending: its source voxel is not in memory yet), or
// kResolvedSample | label.
inline constexpr std::uint32_t kResolvedSample = 0x80000000u;

// The deformed TM scan-converted onto the output's sample lattice, with the
// map of every tet back to the source grid.
class RasterizationPlan {
public:
  // rest: the TM at rest (positions in the source grid frame, mm); deformed:
  // #V deformed positions in the same vertex order. Throws InputError for a
  // vertex count mismatch, non-finite positions or bad connectivity, and for
  // `samples` outside 1..kMaxRasterSamples.
  RasterizationPlan(const GridGeometry& source, const TetMesh& rest, const std::vector<Eigen::Vector3d>& deformed,
                    int samples = 1);

  const GridGeometry& source() const { return source_; }
  const GridGeometry& output() const { return output_; }
  const GridGeometry& lattice() const { return lattice_; }
  int samples() const { return samples_; }
  std::int64_t samplesPerOutputSlice() const { return lattice_.sliceVoxels() * samples_; }

  // #T deformed tets on the sample lattice, in TM order.
  const std::vector<LatticeTet>& tets() const { return tets_; }
  // Rest positions of tet t's vertices in source continuous-index coordinates.
  std::array<Eigen::Vector3d, 4> restCorners(std::int32_t t) const;
  // Sample lattice point -> source continuous index, through tet t.
  TetAffineMap<3> sourceMap(std::int32_t t) const;

  // The tets of output slices [z0, z1) (sample slices k z0 .. k z1).
  SlabTets slab(std::int64_t z0, std::int64_t z1) const;
  // Source slices that the samples of a slab may read (empty when none).
  // Includes a margin for float evaluation.
  SliceRange sourceSlices(const SlabTets& slab) const;

private:
  GridGeometry source_, output_, lattice_;
  int samples_ = 1;
  std::vector<Tet> connectivity_;
  std::vector<Eigen::Vector3d> restIndex_;        // #V rest positions, source index coordinates
  std::vector<LatticeTet> tets_;
  std::vector<std::array<std::int32_t, 2>> sourceZ_;  // #T source slice range [lo, hi], lo > hi: none
};

// Resolve stage: every pending sample of the slab whose source voxel lies in
// source slices [w0, w1) gets its label from `window` (those slices, whole,
// x fastest); samples mapping off the source grid get label 0. `state` holds
// the slab's samples in lattice order.
void resolveSamples(const RasterizationPlan& plan, const SlabTets& slab, const Label* window, std::int64_t w0,
                    std::int64_t w1, std::uint32_t* state, int threads);

// Reduce stage: the label of every output voxel of the slab (majority of its
// samples) into `out` (the slab's output voxels, x fastest).
void reduceSamples(const RasterizationPlan& plan, const SlabTets& slab, const std::uint32_t* state, Label* out,
                   int threads);

// The source windows (at most `capacity` slices each) through which the
// resolve stage reads `needed`, of a source of `sourceSlices` slices: none
// when `needed` is empty; `resident` alone when it holds `needed`; else
// consecutive windows from needed.first, a single one extended to `capacity`
// slices (a whole source that fits is loaded whole) so that the next slabs
// find their slices resident.
std::vector<SliceRange> sourceWindows(const SliceRange& needed, const SliceRange& resident, std::int64_t capacity,
                                      std::int64_t sourceSlices);

// An engine that rasterizes G' slab by slab (the CPU reference below, the GPU
// kernel gpu::RasterizeKernel); the out-of-core driver writes its slabs.
class SlabRasterizer {
public:
  virtual ~SlabRasterizer() = default;
  virtual const GridGeometry& outputGeometry() const = 0;
  // Output slices per slab that fit the engine's memory limits.
  virtual std::int64_t slabSlices() const = 0;
  // Labels of output slices [z0, z1) into out ((z1 - z0) * nx * ny labels).
  virtual void rasterizeSlab(std::int64_t z0, std::int64_t z1, Label* out) = 0;
};

// The whole of G' from `engine`, slab by slab (reports "rasterize" progress).
LabelGrid rasterizeAllSlabs(SlabRasterizer& engine);

struct CpuRasterizerLimits {
  std::int64_t slabSamples = kSlabPoints;             // sample states held at once
  std::int64_t windowVoxels = std::int64_t(1) << 28;  // source labels held at once
};

// The CPU reference as a slab engine reading its source through a
// GridSliceReader (both must outlive it).
class CpuSlabRasterizer : public SlabRasterizer {
public:
  CpuSlabRasterizer(const RasterizationPlan& plan, GridSliceReader& source, const CpuRasterizerLimits& limits = {},
                    int threads = 0);
  const GridGeometry& outputGeometry() const override { return plan_.output(); }
  std::int64_t slabSlices() const override;
  void rasterizeSlab(std::int64_t z0, std::int64_t z1, Label* out) override;

private:
  const RasterizationPlan& plan_;
  GridSliceReader& source_;
  CpuRasterizerLimits limits_;
  int threads_;
  std::vector<std::uint32_t> state_;
  std::vector<Label> window_;
  SliceRange resident_;
};

// In-core CPU reference: the deformed grid G'.
LabelGrid rasterizeDeformedGrid(const LabelGrid& source, const TetMesh& rest, const std::vector<Eigen::Vector3d>& deformed,
                                const RasterizeOptions& options = {});

}  // namespace vox
