#include "geometry/raster/out_of_core.h"

#include "geometry/error.h"
#include "geometry/parallel.h"
#include "geometry/progress.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <future>
#include <unistd.h>

namespace vox {

namespace {

std::string errnoText() { return std::strerror(errno); }

// Full-resolution slices copied to an unlinked raw temporary (native uint16),
// read back in any order.
class SpooledSlices final : public GridSliceReader {
public:
  SpooledSlices(const GridGeometry& geometry, const std::string& directory, const std::string& source)
      : geometry_(geometry), source_(source) {
    std::string name = (std::filesystem::path(directory.empty() ? "." : directory) / "voxmorph-source-XXXXXX").string();
    fd_ = ::mkstemp(name.data());
    if (fd_ < 0) throw RuntimeFailure(name + ": cannot create a temporary copy of " + source + " (" + errnoText() + ")");
    ::unlink(name.c_str());
  }
  ~SpooledSlices() override {
    if (fd_ >= 0) ::close(fd_);
  }
  const GridGeometry& geometry() const override { return geometry_; }

  void append(const Label* slices, std::int64_t count) {
    const char* p = reinterpret_cast<const char*>(slices);
    std::size_t left = std::size_t(count * geometry_.sliceVoxels()) * sizeof(Label);
    while (left > 0) {
      const ssize_t n = ::write(fd_, p, left);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) throw RuntimeFailure("temporary copy of " + source_ + ": write failed (" + errnoText() + ")");
      p += n;
      left -= std::size_t(n);
    }
  }

  void readSlices(std::int64_t k0, std::int64_t count, Label* out) override {
    const std::int64_t slice = geometry_.sliceVoxels() * std::int64_t(sizeof(Label));
    char* p = reinterpret_cast<char*>(out);
    std::size_t left = std::size_t(count * slice);
    off_t offset = off_t(k0 * slice);
    while (left > 0) {
      const ssize_t n = ::pread(fd_, p, left, offset);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) throw RuntimeFailure("temporary copy of " + source_ + ": read failed (" + errnoText() + ")");
      p += n;
      offset += n;
      left -= std::size_t(n);
    }
  }

private:
  GridGeometry geometry_;
  std::string source_;
  int fd_ = -1;
};

GridGeometry downsampledGeometry(const GridGeometry& g, int factor) {
  GridGeometry d = g;
  for (int a = 0; a < 3; ++a) d.dims[std::size_t(a)] = (g.dims[std::size_t(a)] + factor - 1) / factor;
  d.spacing = g.spacing * double(factor);
  d.origin = g.origin + g.spacing * (double(factor - 1) / 2.0);
  return d;
}

// Downsampled slice K from the `count` (<= factor) source slices of its blocks.
void downsampleSlice(const GridGeometry& g, int factor, const Label* slices, std::int64_t count, Label* out) {
  const std::int64_t nx = g.dims[0], ny = g.dims[1];
  const std::int64_t dx = (nx + factor - 1) / factor, dy = (ny + factor - 1) / factor;
  std::vector<Label> block;
  for (std::int64_t J = 0; J < dy; ++J)
    for (std::int64_t I = 0; I < dx; ++I) {
      block.clear();
      for (std::int64_t k = 0; k < count; ++k)
        for (std::int64_t j = J * factor; j < std::min((J + 1) * factor, ny); ++j) {
          const Label* row = slices + (k * ny + j) * nx;
          for (std::int64_t i = I * factor; i < std::min((I + 1) * factor, nx); ++i)
            if (row[i] != 0) block.push_back(row[i]);
        }
      Label best = 0;
      if (!block.empty()) {
        std::sort(block.begin(), block.end());
        std::size_t bestCount = 0;
        for (std::size_t s = 0; s < block.size();) {
          std::size_t e = s;
          while (e < block.size() && block[e] == block[s]) ++e;
          if (e - s > bestCount) best = block[s], bestCount = e - s;
          s = e;
        }
      }
      out[J * dx + I] = best;
    }
}

// One pass over the source in slice order: the downsampled grid, the largest
// label, and every group of slices handed to `visit` (for spooling).
template <class Visit>
LabelGrid streamDownsample(GridSliceReader& source, int factor, Label& maxLabel, Visit&& visit) {
  const GridGeometry& g = source.geometry();
  LabelGrid out(downsampledGeometry(g, factor));
  std::vector<Label> slices(std::size_t(factor * g.sliceVoxels()));
  maxLabel = 0;
  ProgressCounter progress("read source", double(g.dims[2]));
  for (std::int64_t K = 0; K < out.dims()[2]; ++K) {
    const std::int64_t k0 = K * factor, count = std::min<std::int64_t>(factor, g.dims[2] - k0);
    source.readSlices(k0, count, slices.data());
    const std::int64_t n = count * g.sliceVoxels();
    maxLabel = std::max(maxLabel, *std::max_element(slices.begin(), slices.begin() + n));
    visit(slices.data(), count);
    downsampleSlice(g, factor, slices.data(), count, out.data() + K * out.geometry().sliceVoxels());
    progress.advance(double(count));
  }
  progress.finish();
  return out;
}

}  // namespace

LabelGrid downsampleLabels(GridSliceReader& source, int factor) {
  if (factor < 1) throw InputError("downsampling", "factor must be at least 1");
  Label maxLabel;
  return streamDownsample(source, factor, maxLabel, [](const Label*, std::int64_t) {});
}

LabelGrid downsampleLabels(const LabelGrid& source, int factor) {
  if (factor < 1) throw InputError("downsampling", "factor must be at least 1");
  const GridGeometry& g = source.geometry();
  LabelGrid out(downsampledGeometry(g, factor));
  const std::int64_t outSlice = out.geometry().sliceVoxels();
  parallelRanges(out.dims()[2], workerThreads(0), [&](std::int64_t K0, std::int64_t K1) {
    for (std::int64_t K = K0; K < K1; ++K) {
      const std::int64_t k0 = K * factor, count = std::min<std::int64_t>(factor, g.dims[2] - k0);
      downsampleSlice(g, factor, source.data() + k0 * g.sliceVoxels(), count, out.data() + K * outSlice);
    }
  }, 1);
  return out;
}

int downsampleFactor(const GridGeometry& source, std::int64_t maxVoxels) {
  int f = 1;
  while (downsampledGeometry(source, f).voxelCount() > std::max<std::int64_t>(1, maxVoxels)) ++f;
  return f;
}

OutOfCoreSource::OutOfCoreSource(std::unique_ptr<GridSliceReader> reader, const std::string& path, bool seekable,
                                 std::int64_t maxDownsampledVoxels, const std::string& tempDirectory)
    : path_(path) {
  factor_ = vox::downsampleFactor(reader->geometry(), maxDownsampledVoxels);
  // A source that does not seek cheaply is copied to raw as it streams by.
  const std::int64_t sliceVoxels = reader->geometry().sliceVoxels();
  BodyProjectionAccumulator projection(reader->geometry());
  std::int64_t slicesRead = 0;
  auto count = [&](const Label* s, std::int64_t n) {
    for (std::int64_t v = 0; v < n * sliceVoxels; ++v) {
      if (s[v] >= labelCounts_.size()) labelCounts_.resize(std::size_t(s[v]) + 1, 0);
      ++labelCounts_[s[v]];
    }
    projection.addSlices(slicesRead, n, s);
    slicesRead += n;
  };
  if (seekable) {
    downsampled_ = streamDownsample(*reader, factor_, maxLabel_, count);
    slices_ = std::move(reader);
  } else {
    auto spool = std::make_unique<SpooledSlices>(reader->geometry(), tempDirectory, path);
    downsampled_ = streamDownsample(*reader, factor_, maxLabel_, [&](const Label* s, std::int64_t n) {
      spool->append(s, n);
      count(s, n);
    });
    slices_ = std::move(spool);
  }
  projection_ = projection.result();
}

OutOfCoreSource::~OutOfCoreSource() = default;

RasterMemoryLimits rasterMemoryLimits(std::int64_t budgetBytes, int samples) {
  const double k3 = double(samples) * samples * samples;
  RasterMemoryLimits l;
  // Half for the source window; a third for the slab: 4 bytes per sample
  // state and, per voxel, 2 bytes in the engine plus 2 in the writer's slab.
  l.windowVoxels = std::max<std::int64_t>(1, budgetBytes / 2 / std::int64_t(sizeof(Label)));
  l.slabSamples = std::max<std::int64_t>(1, std::int64_t(double(budgetBytes) / 3.0 / (4.0 + 4.0 / k3)));
  return l;
}

void MeasuringRasterizer::rasterizeSlab(std::int64_t z0, std::int64_t z1, Label* out) {
  rasterizeUnmeasured(z0, z1, out);
  measureSlab(z0, z1, out);
}

void MeasuringRasterizer::measureSlab(std::int64_t z0, std::int64_t z1, const Label* slab) {
  projection_.addSlices(z0, z1 - z0, slab);
  const std::int64_t n = (z1 - z0) * outputGeometry().sliceVoxels();
  for (std::int64_t v = 0; v < n; ++v) {
    const Label l = slab[v];
    if (l >= counts_.size()) counts_.resize(std::size_t(l) + 1, 0);
    ++counts_[l];
  }
}

PosedGridMeasures writePosedGrid(SlabRasterizer& engine, GridSliceWriter& sink, bool commit) {
  MeasuringRasterizer measuring(engine);
  const GridGeometry& g = measuring.outputGeometry();
  const std::int64_t nz = g.dims[2], step = std::min(nz, measuring.slabSlices());
  std::vector<Label> slab(std::size_t(step * g.sliceVoxels()));
  ProgressCounter progress("rasterize", double(nz));
  for (std::int64_t z0 = 0; z0 < nz; z0 += step) {
    const std::int64_t z1 = std::min(nz, z0 + step);
    measuring.rasterizeUnmeasured(z0, z1, slab.data());
    std::future<void> writing = std::async(std::launch::async, [&sink, &slab, count = z1 - z0] { sink.writeSlices(slab.data(), count); });
    measuring.measureSlab(z0, z1, slab.data());
    writing.get();
    progress.advance(double(z1 - z0));
  }
  if (commit) sink.commit();
  progress.finish();
  return {measuring.counts(), measuring.projection()};
}

}  // namespace vox
