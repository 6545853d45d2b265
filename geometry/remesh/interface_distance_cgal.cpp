#include "geometry/remesh/interface_distance.h"

#include "geometry/remesh/parallel_ranges.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>
#include <vector>

namespace vox::remesh {

namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

// Boundary facets of every label's region: label -> triangles.
std::map<std::int32_t, std::vector<Triangle>> labelSurfaces(const TetMesh& mesh) {
  struct Face {
    std::array<std::int32_t, 3> sorted;
    std::int32_t label;
    std::size_t tet;
    int k;
  };
  std::vector<Face> faces;
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    if (mesh.labels[t] <= 0) continue;
    for (int k = 0; k < 4; ++k) {
      const Tri f = tetFace(mesh.tets[t], k);
      std::array<std::int32_t, 3> s{f[0], f[1], f[2]};
      std::sort(s.begin(), s.end());
      faces.push_back({s, mesh.labels[t], t, k});
    }
  }
  std::sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) {
    return std::tie(a.sorted, a.label, a.tet, a.k) < std::tie(b.sorted, b.label, b.tet, b.k);
  });
  std::map<std::int32_t, std::vector<Triangle>> out;
  auto add = [&](const Face& f) {
    const Tri v = tetFace(mesh.tets[f.tet], f.k);
    auto p = [&](int i) {
      const Eigen::Vector3d& x = mesh.positions[std::size_t(v[std::size_t(i)])];
      return Point(x[0], x[1], x[2]);
    };
    out[f.label].emplace_back(p(0), p(1), p(2));
  };
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].sorted == faces[i].sorted) ++j;
    if (j - i == 1) add(faces[i]);
    else if (faces[i].label != faces[i + 1].label) {
      add(faces[i]);
      add(faces[i + 1]);
    }
    i = j;
  }
  return out;
}

// Largest distance from samples of `from` to the surface `to`.
double oneSided(const std::vector<Triangle>& from, const Tree& to, std::size_t maxSamples) {
  const std::size_t stride = std::max<std::size_t>(1, (from.size() + maxSamples - 1) / maxSamples);
  double worst = 0.0;
  for (std::size_t i = 0; i < from.size(); i += stride) {
    const Triangle& t = from[i];
    const Point c = CGAL::centroid(t);
    const Point samples[7] = {t[0], t[1], t[2], CGAL::midpoint(t[0], t[1]), CGAL::midpoint(t[1], t[2]),
                              CGAL::midpoint(t[2], t[0]), c};
    for (const Point& s : samples) worst = std::max(worst, to.squared_distance(s));
  }
  return std::sqrt(worst);
}

}  // namespace

std::map<std::int32_t, InterfaceDistance> interfaceDistances(const TetMesh& input, const TetMesh& output,
                                                             std::size_t maxSamples, int threads) {
  const auto a = labelSurfaces(input);
  const auto b = labelSurfaces(output);
  std::vector<std::int32_t> labels;
  for (const auto& [label, tris] : a)
    if (b.count(label)) labels.push_back(label);
  std::vector<InterfaceDistance> result(labels.size());
  parallelRanges(std::int64_t(labels.size()), threads, [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      const auto& in = a.at(labels[std::size_t(i)]);
      const auto& out = b.at(labels[std::size_t(i)]);
      Tree inTree(in.begin(), in.end()), outTree(out.begin(), out.end());
      inTree.accelerate_distance_queries();
      outTree.accelerate_distance_queries();
      result[std::size_t(i)].outputToInput = oneSided(out, inTree, maxSamples);
      result[std::size_t(i)].inputToOutput = oneSided(in, outTree, maxSamples);
    }
  }, 1);
  std::map<std::int32_t, InterfaceDistance> out;
  for (std::size_t i = 0; i < labels.size(); ++i) out[labels[i]] = result[i];
  return out;
}

}  // namespace vox::remesh
