#include "geometry/io/sizing_grid_io.h"

#include "geometry/error.h"
#include "geometry/io/grid_stream.h"
#include "geometry/io/nifti_header.h"

#include <algorithm>
#include <cstdint>
#include <vector>

namespace vox {

ScalarGrid readSizingGrid(const std::string& path) {
  // The label grid reader's header check: dims, sample type, the affine, and
  // the bytes the file can hold, all before the values are allocated.
  const std::unique_ptr<ByteReader> in = openNiftiBytes(path);
  const NiftiLayout layout = parseNiftiHeader(path, *in, kNiftiSizes);
  checkSamplesFit(path, layout.geometry, layout.encoding.type, *in, layout.dataOffset);
  in->seek(layout.dataOffset);

  ScalarGrid grid;
  grid.geometry = layout.geometry;
  const std::int64_t count = grid.geometry.voxelCount();
  grid.values.resize(std::size_t(count));
  const int size = voxelTypeSize(layout.encoding.type);
  constexpr std::int64_t kChunk = std::int64_t(1) << 20;
  std::vector<char> raw;
  for (std::int64_t done = 0; done < count;) {
    const std::int64_t n = std::min(kChunk, count - done);
    raw.resize(std::size_t(n * size));
    const std::size_t got = in->read(raw.data(), raw.size());
    if (got != raw.size())
      throw InputError(path, "voxel data is truncated: it ends at voxel " + std::to_string(done + std::int64_t(got) / size) + " of " +
                                 std::to_string(count));
    decodeValues(layout.encoding, raw.data(), n, grid.values.data() + done);
    done += n;
  }
  in->checkEnd();
  return grid;
}

}  // namespace vox
