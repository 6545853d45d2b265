#include "geometry/remesh/face_adjacency.h"

#include "geometry/cancellation.h"
#include "geometry/error.h"

#include <algorithm>

namespace vox::remesh {

std::string describeTet(std::size_t t, const Tet& q) {
  return "tet " + std::to_string(t) + " (vertices " + std::to_string(q[0]) + ", " + std::to_string(q[1]) + ", " +
         std::to_string(q[2]) + ", " + std::to_string(q[3]) + ")";
}

std::vector<std::array<std::int32_t, 4>> tetFaceAdjacency(const std::vector<Tet>& tets, std::int32_t vertexCount,
                                                           const std::string& source) {
  const std::size_t nt = tets.size();
  std::vector<std::array<std::int32_t, 4>> adjacency = filledCancellable(nt, std::array<std::int32_t, 4>{kNoFace, kNoFace, kNoFace, kNoFace});

  // Counting sort of the 4 #T faces on their smallest vertex.
  std::vector<std::int64_t> start(std::size_t(vertexCount) + 1, 0);
  auto sortedFace = [&](std::size_t t, int k) {
    std::array<std::int32_t, 3> f{};
    int n = 0;
    for (int i = 0; i < 4; ++i)
      if (i != k) f[n++] = tets[t][i];
    std::sort(f.begin(), f.end());
    return f;
  };
  for (std::size_t t = 0; t < nt; ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    for (int k = 0; k < 4; ++k) ++start[std::size_t(sortedFace(t, k)[0]) + 1];
  }
  for (std::size_t v = 0; v < std::size_t(vertexCount); ++v) start[v + 1] += start[v];

  struct Entry {
    std::uint64_t key;  // the two larger vertices
    std::int32_t face;  // 4 * tet + k
  };
  std::vector<Entry> entries = filledCancellable(4 * nt, Entry{});
  std::vector<std::int64_t> fill(start.begin(), start.end() - 1);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 4; ++k) {
      if (k == 0 && t % 4096 == 0) throwIfCancelled();  // a second and more on millions of tets
      const auto f = sortedFace(t, k);
      entries[std::size_t(fill[std::size_t(f[0])]++)] = {(std::uint64_t(std::uint32_t(f[1])) << 32) | std::uint32_t(f[2]),
                                                           std::int32_t(4 * t + std::size_t(k))};
    }

  for (std::size_t v = 0; v < std::size_t(vertexCount); ++v) {
    if (v % 4096 == 0) throwIfCancelled();
    Entry* b = entries.data() + start[v];
    Entry* e = entries.data() + start[v + 1];
    std::sort(b, e, [](const Entry& x, const Entry& y) { return x.key < y.key || (x.key == y.key && x.face < y.face); });
    for (Entry* p = b; p < e;) {
      Entry* q = p + 1;
      while (q < e && q->key == p->key) ++q;
      if (q - p > 2) {
        const std::size_t t = std::size_t(q[-1].face / 4);
        const std::uint64_t key = p->key;
        throw InputError(source, describeTet(t, tets[t]) + " shares face (" + std::to_string(v) + ", " +
                                     std::to_string(key >> 32) + ", " + std::to_string(key & 0xffffffffu) + ") with tet " +
                                     std::to_string(p[0].face / 4) + " and tet " + std::to_string(p[1].face / 4) +
                                     ": a face shared by more than two tets");
      }
      if (q - p == 2) {
        adjacency[std::size_t(p[0].face / 4)][std::size_t(p[0].face % 4)] = p[1].face;
        adjacency[std::size_t(p[1].face / 4)][std::size_t(p[1].face % 4)] = p[0].face;
      }
      p = q;
    }
  }
  return adjacency;
}

}  // namespace vox::remesh
