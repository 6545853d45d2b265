#include "geometry/remesh/mesh_topology.h"
#include "geometry/disjoint_sets.h"

#include "geometry/remesh/element_classification.h"
#include "geometry/remesh/face_adjacency.h"
#include "geometry/remesh/label_set.h"

#include "geometry/cancellation.h"

#include <algorithm>
#include <numeric>

namespace vox::remesh {

namespace {

std::vector<std::int32_t> toVector(const LabelSet& s) { return {s.begin(), s.end()}; }

// Feature edges (v, u) with their label sets, grouped by label set: counts
// the connected components of each group.
void countJunctionCurves(std::vector<std::pair<std::vector<std::int32_t>, std::pair<std::int64_t, std::int64_t>>>& edges,
                         MeshTopology& out) {
  sortCancellable(edges.begin(), edges.end());
  out.featureEdges = edges.size();
  std::vector<std::int64_t> vertices;
  for (std::size_t b = 0; b < edges.size();) {
    std::size_t e = b;
    while (e < edges.size() && edges[e].first == edges[b].first) ++e;
    vertices.clear();
    for (std::size_t i = b; i < e; ++i) {
      vertices.push_back(edges[i].second.first);
      vertices.push_back(edges[i].second.second);
    }
    std::sort(vertices.begin(), vertices.end());
    vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
    auto local = [&](std::int64_t v) {
      return std::int32_t(std::lower_bound(vertices.begin(), vertices.end(), v) - vertices.begin());
    };
    DisjointSets sets(vertices.size());
    for (std::size_t i = b; i < e; ++i) sets.unite(local(edges[i].second.first), local(edges[i].second.second));
    std::size_t components = 0;
    for (std::size_t i = 0; i < vertices.size(); ++i) components += sets.find(std::int32_t(i)) == std::int32_t(i);
    out.junctionCurves[edges[b].first] = components;
    b = e;
  }
}

}  // namespace

MeshTopology computeMeshTopology(const TetMesh& input) {
  MeshTopology out;
  // Domain tets only; vertices compacted.
  std::vector<Tet> tets;
  std::vector<std::int32_t> labels;
  for (std::size_t t = 0; t < input.tets.size(); ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    if (input.labels[t] > 0) {
      tets.push_back(input.tets[t]);
      labels.push_back(input.labels[t]);
    }
  }
  const std::int32_t nv = std::int32_t(input.positions.size());
  const std::size_t nt = tets.size();
  const auto adjacency = tetFaceAdjacency(tets, nv, "mesh");

  // Simplex counts of each label's closed region: chi = V - E + F - T.
  struct Counts {
    std::int64_t v = 0, e = 0, f = 0, t = 0;
  };
  std::map<std::int32_t, Counts> counts;
  DisjointSets components(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    ++counts[labels[t]].t;
    for (int k = 0; k < 4; ++k) {
      const std::int32_t code = adjacency[t][std::size_t(k)];
      const std::int32_t n = code < 0 ? -1 : code / 4;
      if (n >= 0 && labels[std::size_t(n)] == labels[t]) components.unite(std::int32_t(t), n);
      if (n >= 0 && std::size_t(n) < t) continue;  // each face once
      ++counts[labels[t]].f;
      if (n >= 0 && labels[std::size_t(n)] != labels[t]) ++counts[labels[std::size_t(n)]].f;
    }
  }
  for (std::size_t t = 0; t < nt; ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    LabelTopology& lt = out.labels[labels[t]];
    ++lt.tets;
    if (components.find(std::int32_t(t)) == std::int32_t(t)) ++lt.components;
  }

  // Vertex -> tets, and which vertices/edges lie on the domain boundary.
  const VertexTets around = vertexTets(tets, std::size_t(nv));
  const std::vector<std::int64_t>& start = around.start;
  const std::vector<std::int32_t>& incident = around.tets;

  std::vector<std::pair<std::vector<std::int32_t>, std::pair<std::int64_t, std::int64_t>>> featureEdges;
  std::vector<std::int32_t> nbr;
  std::vector<LabelSet> nbrLabels;
  for (std::int32_t v = 0; v < nv; ++v) {
    if (v % 16384 == 0) throwIfCancelled();
    if (start[std::size_t(v)] == start[std::size_t(v) + 1]) continue;
    LabelSet sv;
    nbr.clear();
    nbrLabels.clear();
    for (std::int64_t i = start[std::size_t(v)]; i < start[std::size_t(v) + 1]; ++i) {
      const std::int32_t t = incident[std::size_t(i)];
      const Tet& q = tets[std::size_t(t)];
      sv.insert(labels[std::size_t(t)]);
      const int kv = q[0] == v ? 0 : q[1] == v ? 1 : q[2] == v ? 2 : 3;
      for (int ku = 0; ku < 4; ++ku) {
        if (ku == kv) continue;
        const std::int32_t u = q[std::size_t(ku)];
        std::size_t j = 0;
        while (j < nbr.size() && nbr[j] != u) ++j;
        if (j == nbr.size()) {
          nbr.push_back(u);
          nbrLabels.emplace_back();
        }
        nbrLabels[j].insert(labels[std::size_t(t)]);
        // The two faces of q holding edge (v, u) are opposite its other two
        // vertices: an open one puts the edge on the domain boundary.
        for (int kf = 0; kf < 4; ++kf)
          if (kf != kv && kf != ku && adjacency[std::size_t(t)][std::size_t(kf)] < 0) {
            nbrLabels[j].insert(kBackgroundLabel);
            sv.insert(kBackgroundLabel);
          }
      }
    }
    for (std::int32_t l : sv)
      if (l > 0) ++counts[l].v;
    int feature = 0;
    bool agree = true;
    for (std::size_t j = 0; j < nbr.size(); ++j) {
      if (!isFeatureEdge(nbrLabels[j])) continue;
      ++feature;
      agree = agree && nbrLabels[j] == *std::find_if(nbrLabels.begin(), nbrLabels.end(), isFeatureEdge);
      if (nbr[j] > v) featureEdges.push_back({toVector(nbrLabels[j]), {v, nbr[j]}});
    }
    for (std::size_t j = 0; j < nbr.size(); ++j)
      if (nbr[j] > v)
        for (std::int32_t l : nbrLabels[j])
          if (l > 0) ++counts[l].e;
    if (classifyVertex(sv.size(), feature, agree) == VertexKind::Corner) ++out.junctionPoints[toVector(sv)];
  }
  for (auto& [label, c] : counts) out.labels[label].euler = c.v - c.e + c.f - c.t;
  countJunctionCurves(featureEdges, out);
  return out;
}

MeshTopology computeGridTopology(const LabelGrid& grid) {
  MeshTopology out;
  const Index3 d = grid.dims();
  const std::int64_t nx = d[0], ny = d[1], nz = d[2];
  auto at = [&](std::int64_t i, std::int64_t j, std::int64_t k) -> std::int32_t { return grid.atOr(i, j, k, 0); };

  // Voxels (T) and face-connected components.
  DisjointSets components(std::size_t(grid.voxelCount()));
  for (std::int64_t k = 0; k < nz; ++k, throwIfCancelled())
    for (std::int64_t j = 0; j < ny; ++j)
      for (std::int64_t i = 0; i < nx; ++i) {
        const std::int32_t l = at(i, j, k);
        if (l == 0) continue;
        LabelTopology& lt = out.labels[l];
        ++lt.tets;
        --lt.euler;
        const std::int32_t idx = std::int32_t(grid.geometry().index(i, j, k));
        if (i > 0 && at(i - 1, j, k) == l) components.unite(idx, std::int32_t(grid.geometry().index(i - 1, j, k)));
        if (j > 0 && at(i, j - 1, k) == l) components.unite(idx, std::int32_t(grid.geometry().index(i, j - 1, k)));
        if (k > 0 && at(i, j, k - 1) == l) components.unite(idx, std::int32_t(grid.geometry().index(i, j, k - 1)));
      }
  for (std::int64_t idx = 0; idx < grid.voxelCount(); ++idx) {
    if (idx % 65536 == 0) throwIfCancelled();
    const std::int32_t l = grid.data()[idx];
    if (l != 0 && components.find(std::int32_t(idx)) == std::int32_t(idx)) ++out.labels[l].components;
  }

  // Cubical cells of every closed region: a lattice point, edge or face
  // belongs to each label among the voxels around it.
  auto addCell = [&](const LabelSet& s, int sign) {
    for (std::int32_t l : s)
      if (l > 0) out.labels[l].euler += sign;
  };
  // Faces: perpendicular to axis a, between voxel (c - e_a) and c.
  for (int a = 0; a < 3; ++a)
    for (std::int64_t k = 0; k <= nz - (a != 2); ++k, throwIfCancelled())
      for (std::int64_t j = 0; j <= ny - (a != 1); ++j)
        for (std::int64_t i = 0; i <= nx - (a != 0); ++i) {
          LabelSet s;
          s.insert(at(i, j, k));
          s.insert(at(i - (a == 0), j - (a == 1), k - (a == 2)));
          addCell(s, +1);
        }
  // Edges along axis a from lattice point (i,j,k); the 4 voxels around it.
  std::vector<std::pair<std::vector<std::int32_t>, std::pair<std::int64_t, std::int64_t>>> featureEdges;
  const std::int64_t cx = nx + 1, cy = ny + 1;
  auto point = [&](std::int64_t i, std::int64_t j, std::int64_t k) { return i + cx * (j + cy * k); };
  auto edgeLabels = [&](int a, std::int64_t i, std::int64_t j, std::int64_t k) {
    LabelSet s;
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    for (int db = 0; db < 2; ++db)
      for (int dc = 0; dc < 2; ++dc) {
        std::int64_t p[3] = {i, j, k};
        p[b] -= db;
        p[c] -= dc;
        s.insert(at(p[0], p[1], p[2]));
      }
    return s;
  };
  for (int a = 0; a < 3; ++a)
    for (std::int64_t k = 0; k <= nz - (a == 2); ++k, throwIfCancelled())
      for (std::int64_t j = 0; j <= ny - (a == 1); ++j)
        for (std::int64_t i = 0; i <= nx - (a == 0); ++i) {
          const LabelSet s = edgeLabels(a, i, j, k);
          addCell(s, -1);
          if (isFeatureEdge(s))
            featureEdges.push_back({toVector(s), {point(i, j, k), point(i + (a == 0), j + (a == 1), k + (a == 2))}});
        }
  // Lattice points: the 8 voxels around, and the 6 axis edges for corners.
  for (std::int64_t k = 0; k <= nz; ++k, throwIfCancelled())
    for (std::int64_t j = 0; j <= ny; ++j)
      for (std::int64_t i = 0; i <= nx; ++i) {
        LabelSet s;
        for (int dz = 0; dz < 2; ++dz)
          for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx) s.insert(at(i - dx, j - dy, k - dz));
        addCell(s, +1);
        if (s.size() < 3) continue;
        int feature = 0;
        bool agree = true;
        LabelSet first;
        for (int a = 0; a < 3; ++a)
          for (const LabelSet& e : {edgeLabels(a, i, j, k), edgeLabels(a, i - (a == 0), j - (a == 1), k - (a == 2))}) {
            if (!isFeatureEdge(e)) continue;
            if (feature++ == 0) first = e;
            else agree = agree && e == first;
          }
        if (classifyVertex(s.size(), feature, agree) == VertexKind::Corner) ++out.junctionPoints[toVector(s)];
      }
  countJunctionCurves(featureEdges, out);
  return out;
}

std::vector<std::string> compareTopology(const MeshTopology& expected, const MeshTopology& actual) {
  std::vector<std::string> diff;
  auto setName = [](const std::vector<std::int32_t>& s) {
    std::string n = "{";
    for (std::size_t i = 0; i < s.size(); ++i) n += (i ? "," : "") + std::to_string(s[i]);
    return n + "}";
  };
  for (const auto& [label, e] : expected.labels) {
    auto it = actual.labels.find(label);
    if (it == actual.labels.end()) {
      diff.push_back("label " + std::to_string(label) + " is missing");
      continue;
    }
    if (it->second.components != e.components)
      diff.push_back("label " + std::to_string(label) + ": " + std::to_string(it->second.components) +
                     " components, expected " + std::to_string(e.components));
    if (it->second.euler != e.euler)
      diff.push_back("label " + std::to_string(label) + ": Euler characteristic " + std::to_string(it->second.euler) +
                     ", expected " + std::to_string(e.euler));
  }
  for (const auto& [label, a] : actual.labels)
    if (!expected.labels.count(label)) diff.push_back("label " + std::to_string(label) + " is new");
  auto compareCounts = [&](const std::map<std::vector<std::int32_t>, std::size_t>& e,
                           const std::map<std::vector<std::int32_t>, std::size_t>& a, const char* what) {
    for (const auto& [set, count] : e) {
      auto it = a.find(set);
      const std::size_t got = it == a.end() ? 0 : it->second;
      if (got != count)
        diff.push_back(std::string(what) + " " + setName(set) + ": " + std::to_string(got) + ", expected " +
                       std::to_string(count));
    }
    for (const auto& [set, count] : a)
      if (!e.count(set)) diff.push_back(std::string(what) + " " + setName(set) + ": " + std::to_string(count) + ", expected 0");
  };
  compareCounts(expected.junctionCurves, actual.junctionCurves, "1-junction components");
  compareCounts(expected.junctionPoints, actual.junctionPoints, "0-junctions");
  return diff;
}

}  // namespace vox::remesh
