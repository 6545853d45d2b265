#include "geometry/remesh/feature_edges.h"

#include "geometry/disjoint_sets.h"
#include "geometry/error.h"
#include "geometry/remesh/element_classification.h"
#include "geometry/remesh/remesh_complex.h"
#include "geometry/remesh/split_long_edges.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <queue>
#include <tuple>
#include <unordered_map>

namespace vox::remesh {

std::int32_t FeatureEdges::addLine(std::vector<FeatureSegment> segments) {
  geometry_.push_back(std::move(segments));
  return std::int32_t(geometry_.size()) - 1;
}

void FeatureEdges::addDegree(std::int32_t v, int delta) {
  if (std::size_t(v) >= degree_.size()) degree_.resize(std::size_t(v) + 1 + std::size_t(v) / 4, 0);
  const int d = int(degree_[std::size_t(v)]) + delta;
  degree_[std::size_t(v)] = std::uint8_t(std::clamp(d, 0, 255));
}

void FeatureEdges::tag(std::int32_t a, std::int32_t b, std::int32_t line) {
  const auto [it, added] = lines_.try_emplace(key(a, b), line);
  if (!added) {
    it->second = line;
    return;
  }
  addDegree(a, 1);
  addDegree(b, 1);
}

void FeatureEdges::untag(std::int32_t a, std::int32_t b) {
  if (lines_.erase(key(a, b)) == 0) return;
  addDegree(a, -1);
  addDegree(b, -1);
}

void FeatureEdges::split(std::int32_t a, std::int32_t b, std::int32_t m) {
  const std::int32_t line = lineOf(a, b);
  if (line < 0) return;
  untag(a, b);
  tag(a, m, line);
  tag(m, b, line);
}

void FeatureEdges::merge(std::int32_t removed, std::int32_t kept, const std::vector<std::int32_t>& removedNeighbors) {
  if (degree(removed) == 0) return;
  untag(removed, kept);
  for (std::int32_t w : removedNeighbors) {
    if (w == kept) continue;
    const std::int32_t line = lineOf(removed, w);
    if (line < 0) continue;
    untag(removed, w);
    // A common neighbour's two edges become one: tagged when either was.
    if (lineOf(kept, w) < 0) tag(kept, w, line);
  }
}

void FeatureEdges::setCorner(std::int32_t v) {
  if (std::size_t(v) >= corner_.size()) corner_.resize(std::size_t(v) + 1 + std::size_t(v) / 4, 0);
  corner_[std::size_t(v)] = 1;
}

void FeatureEdges::markKinks(const std::vector<Eigen::Vector3d>& positions, double angleDeg) {
  // The two tagged neighbours of every vertex of degree 2.
  std::unordered_map<std::int32_t, std::vector<std::int32_t>> ends;
  for (const auto& [k, line] : lines_) {
    const std::int32_t a = std::int32_t(k >> 32), b = std::int32_t(k & 0xFFFFFFFFu);
    if (degree(a) == 2) ends[a].push_back(b);
    if (degree(b) == 2) ends[b].push_back(a);
  }
  const double straight = std::cos(angleDeg * M_PI / 180.0);
  for (const auto& [v, w] : ends) {
    if (w.size() != 2 || lineOf(v, w[0]) != lineOf(v, w[1])) continue;
    const Eigen::Vector3d in = positions[std::size_t(v)] - positions[std::size_t(w[0])];
    const Eigen::Vector3d out = positions[std::size_t(w[1])] - positions[std::size_t(v)];
    if (!(in.normalized().dot(out.normalized()) >= straight)) setCorner(v);
  }
}

void FeatureEdges::renumber(const std::vector<std::int32_t>& vmap) {
  std::unordered_map<std::uint64_t, std::int32_t> lines;
  lines.reserve(lines_.size());
  std::vector<std::uint8_t> degree(vmap.size(), 0);
  for (const auto& [k, line] : lines_) {
    const std::int32_t a = vmap[std::size_t(k >> 32)], b = vmap[std::size_t(k & 0xFFFFFFFFu)];
    if (a < 0 || b < 0) continue;
    lines.emplace(key(a, b), line);
    for (std::int32_t v : {a, b})
      if (std::size_t(v) >= degree.size()) degree.resize(std::size_t(v) + 1, 0);
    degree[std::size_t(a)] = std::uint8_t(std::min(255, degree[std::size_t(a)] + 1));
    degree[std::size_t(b)] = std::uint8_t(std::min(255, degree[std::size_t(b)] + 1));
  }
  lines_ = std::move(lines);
  degree_ = std::move(degree);
  std::vector<std::uint8_t> corner(vmap.size(), 0);
  for (std::size_t v = 0; v < corner_.size() && v < vmap.size(); ++v)
    if (corner_[v] && vmap[v] >= 0) {
      if (std::size_t(vmap[v]) >= corner.size()) corner.resize(std::size_t(vmap[v]) + 1, 0);
      corner[std::size_t(vmap[v])] = 1;
    }
  corner_ = std::move(corner);
}

namespace {

Eigen::Vector3d closestOnSegment(const FeatureSegment& s, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = s[1] - s[0];
  const double len2 = d.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - s[0]).dot(d) / len2, 0.0, 1.0) : 0.0;
  return s[0] + t * d;
}

}  // namespace

Eigen::Vector3d FeatureEdges::projectOnLine(std::int32_t line, const Eigen::Vector3d& p) const {
  Eigen::Vector3d best = p;
  double bestDistance = std::numeric_limits<double>::infinity();
  for (const FeatureSegment& s : geometry_[std::size_t(line)]) {
    const Eigen::Vector3d q = closestOnSegment(s, p);
    const double d = (q - p).squaredNorm();
    if (d < bestDistance) {
      bestDistance = d;
      best = q;
    }
  }
  return best;
}

std::vector<TaggedEdge> FeatureEdges::list() const {
  std::vector<TaggedEdge> out;
  out.reserve(lines_.size());
  for (const auto& [k, line] : lines_) out.push_back({std::int32_t(k >> 32), std::int32_t(k & 0xFFFFFFFFu), line});
  std::sort(out.begin(), out.end(),
            [](const TaggedEdge& x, const TaggedEdge& y) { return std::tie(x.line, x.a, x.b) < std::tie(y.line, y.a, y.b); });
  return out;
}

std::size_t tagSharpFeatures(RemeshComplex& complex, double angleDeg, double minPatchArea) {
  // The outer boundary facets, with their outward unit normals.
  std::vector<Tri> facets;
  std::vector<Eigen::Vector3d> normals;
  for (std::int32_t t = 0; t < complex.tetSlots(); ++t) {
    if (!complex.tetAlive(t) || complex.isDummyTet(t) || complex.label(t) <= 0) continue;
    for (int k = 0; k < 4; ++k) {
      if (complex.label(complex.neighbor(t, k)) != kBackgroundLabel) continue;
      const Tri f = tetFace(complex.tet(t), k);
      const Eigen::Vector3d a = complex.position(f[0]);
      facets.push_back(f);
      normals.push_back((complex.position(f[1]) - a).cross(complex.position(f[2]) - a).normalized());
    }
  }
  // Facets by edge: a manifold boundary edge has two.
  std::vector<std::tuple<std::int32_t, std::int32_t, std::int32_t>> edges;
  edges.reserve(3 * facets.size());
  for (std::size_t i = 0; i < facets.size(); ++i)
    for (int e = 0; e < 3; ++e) {
      const auto [a, b] = std::minmax(facets[i][std::size_t(e)], facets[i][std::size_t((e + 1) % 3)]);
      edges.emplace_back(a, b, std::int32_t(i));
    }
  std::sort(edges.begin(), edges.end());
  const double joined = std::cos(angleDeg * M_PI / 180.0);
  DisjointSets patches(facets.size());
  auto forEachManifoldEdge = [&](const auto& visit) {
    for (std::size_t i = 0; i < edges.size();) {
      std::size_t j = i + 1;
      while (j < edges.size() && std::get<0>(edges[j]) == std::get<0>(edges[i]) &&
             std::get<1>(edges[j]) == std::get<1>(edges[i]))
        ++j;
      // Edges met by more than two outer facets are contacts, pinned already.
      if (j - i == 2) visit(std::get<0>(edges[i]), std::get<1>(edges[i]), std::get<2>(edges[i]), std::get<2>(edges[i + 1]));
      i = j;
    }
  };
  forEachManifoldEdge([&](std::int32_t, std::int32_t, std::int32_t f, std::int32_t g) {
    if (normals[std::size_t(f)].dot(normals[std::size_t(g)]) > joined) patches.unite(f, g);
  });
  // Patches smaller than minPatchArea join the neighbour they share the
  // longest boundary with (ties: the smaller id), until none is left.
  std::vector<double> facetArea(facets.size());
  for (std::size_t i = 0; i < facets.size(); ++i) {
    const Eigen::Vector3d a = complex.position(facets[i][0]);
    facetArea[i] = 0.5 * (complex.position(facets[i][1]) - a).cross(complex.position(facets[i][2]) - a).norm();
  }
  for (bool merged = true; merged;) {
    merged = false;
    std::map<std::int32_t, double> area;
    for (std::size_t i = 0; i < facets.size(); ++i) area[patches.find(std::int32_t(i))] += facetArea[i];
    std::map<std::pair<std::int32_t, std::int32_t>, double> shared;
    forEachManifoldEdge([&](std::int32_t a, std::int32_t b, std::int32_t f, std::int32_t g) {
      const std::int32_t p = patches.find(f), q = patches.find(g);
      if (p == q) return;
      const double length = (complex.position(a) - complex.position(b)).norm();
      shared[{p, q}] += length;
      shared[{q, p}] += length;
    });
    std::map<std::int32_t, std::pair<double, std::int32_t>> best;  // small patch -> (shared length, neighbour)
    for (const auto& [pq, length] : shared) {
      if (area[pq.first] >= minPatchArea) continue;
      auto [it, added] = best.try_emplace(pq.first, length, pq.second);
      if (!added && length > it->second.first) it->second = {length, pq.second};
    }
    for (const auto& [p, choice] : best) merged = patches.unite(p, choice.second) || merged;
  }
  // One line per pair of patches, in order of the pairs (patch ids are their
  // smallest facet index, so the numbering depends only on the complex).
  std::map<std::pair<std::int32_t, std::int32_t>, std::vector<std::pair<std::int32_t, std::int32_t>>> byPair;
  forEachManifoldEdge([&](std::int32_t a, std::int32_t b, std::int32_t f, std::int32_t g) {
    const std::int32_t p = patches.find(f), q = patches.find(g);
    if (p != q) byPair[std::minmax(p, q)].push_back({a, b});
  });
  FeatureEdges& features = complex.features();
  for (const auto& [pair, lineEdges] : byPair) {
    std::vector<FeatureSegment> segments;
    for (const auto& [a, b] : lineEdges) segments.push_back({complex.position(a), complex.position(b)});
    const std::int32_t line = features.addLine(std::move(segments));
    for (const auto& [a, b] : lineEdges) features.tag(a, b, line);
  }
  features.markKinks(complex.positions(), angleDeg);
  return byPair.size();
}

namespace {

double distanceToSegment(const FeatureSegment& s, const Eigen::Vector3d& p) { return (closestOnSegment(s, p) - p).norm(); }

std::string formatPoint(const Eigen::Vector3d& p) {
  char text[96];
  std::snprintf(text, sizeof text, "(%g, %g, %g)", p.x(), p.y(), p.z());
  return text;
}

// The point of segment [p0, p1] closest to segment [q0, q1], and its
// parameter t along [p0, p1].
Eigen::Vector3d closestBetweenSegments(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0,
                                       const Eigen::Vector3d& q1, double& t) {
  const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r), c = d1.dot(r), b = d1.dot(d2);
  const double denom = a * e - b * b;
  t = denom > 1e-12 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  double u = e > 0.0 ? (b * t + f) / e : 0.0;
  if (u < 0.0 || u > 1.0) {
    u = std::clamp(u, 0.0, 1.0);
    t = a > 0.0 ? std::clamp((b * u - c) / a, 0.0, 1.0) : 0.0;
  }
  return p0 + t * d1;
}

// Splits, for each inner path vertex farther than tolerance / 40 from the
// path's segment, the edge near it (up to 8 vertices away, along edges
// whose label sets lie in the vertex's: on a boundary vertex's junction or
// interfaces, not into a label) that passes closest to the segment, at that
// closest point, when it is inside the edge and at most half as far from
// the segment as the vertex. The new vertex has the edge's label set, so
// the split changes no junction.
// Returns the number of splits.
std::size_t splitCrossings(RemeshComplex& complex, const std::vector<FeatureSegment>& segments,
                           const std::vector<std::vector<std::int32_t>>& walks, double tolerance) {
  std::map<std::pair<std::int32_t, std::int32_t>, Eigen::Vector3d> splits;
  VertexNeighborhood nb;
  for (std::size_t s = 0; s < segments.size(); ++s)
    for (std::size_t i = 1; i + 1 < walks[s].size(); ++i) {
      const std::int32_t v = walks[s][i];
      if (complex.isPinned(v)) continue;
      const Eigen::Vector3d pv = complex.position(v);
      const double off = distanceToSegment(segments[s], pv);
      if (!(off > tolerance / 40.0)) continue;
      gatherNeighborhood(complex, v, nb);
      if (nb.labels.overflow()) continue;
      const LabelSet stratum = nb.labels;
      // The edges of v's junction or interface (or label) within a few
      // steps of v: the segment may cross them an edge or two away from the
      // vertex the path went through.
      double best = 0.5 * off;
      std::pair<std::int32_t, std::int32_t> bestEdge{-1, -1};
      Eigen::Vector3d bestQ = pv;
      std::vector<std::int32_t> reached{v};
      for (std::size_t r = 0; r < reached.size() && r < 8; ++r) {
        const std::int32_t x = reached[r];
        if (x != v) gatherNeighborhood(complex, x, nb);
        for (std::size_t k = 0; k < nb.neighbors.size(); ++k) {
          const std::int32_t w = nb.neighbors[k];
          const LabelSet& edge = nb.edgeLabels[k];
          if (w == complex.dummyVertex() || edge.overflow() || !edge.subsetOf(stratum) ||
              edge.size() < std::min(2, stratum.size()))
            continue;
          if (std::find(reached.begin(), reached.end(), w) == reached.end()) reached.push_back(w);
          double t = 0.0;
          const Eigen::Vector3d q =
              closestBetweenSegments(complex.position(x), complex.position(w), segments[s][0], segments[s][1], t);
          const double d = distanceToSegment(segments[s], q);
          if (t > 0.05 && t < 0.95 && d < best) best = d, bestEdge = std::minmax(x, w), bestQ = q;
        }
      }
      if (bestEdge.first >= 0) splits.try_emplace(bestEdge, bestQ);
    }
  std::size_t made = 0;
  EdgeRing ring;
  for (const auto& [e, q] : splits) {
    const std::int32_t t = complex.findEdgeTet(e.first, e.second);
    if (t < 0) continue;
    complex.edgeRing(e.first, e.second, t, ring);
    if (splitChangesAContact(complex, ring)) continue;
    const std::int32_t m = splitEdge(complex, e.first, e.second, t);
    complex.setPosition(m, q);
    ++made;
  }
  return made;
}

}  // namespace

std::size_t tagPolylines(RemeshComplex& complex, const std::vector<FeatureSegment>& segments, double tolerance,
                         double angleDeg, const std::string& source) {
  // Lines: segments joined at shared end points.
  std::map<std::array<double, 3>, std::int32_t> pointIds;
  std::vector<std::array<std::int32_t, 2>> ends(segments.size());
  for (std::size_t s = 0; s < segments.size(); ++s)
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector3d& p = segments[s][std::size_t(k)];
      ends[s][std::size_t(k)] = pointIds.try_emplace({p.x(), p.y(), p.z()}, std::int32_t(pointIds.size())).first->second;
    }
  DisjointSets joined(pointIds.size());
  for (const auto& e : ends) joined.unite(e[0], e[1]);

  // The vertices of domain tets, the edges between them, and those vertices
  // in cells of `tolerance` (the nearest one within reach of a point is in
  // the 27 cells around it); built again after the crossings are split.
  std::int32_t nv = 0;
  std::vector<char> domain;
  std::vector<std::pair<std::int32_t, std::int32_t>> edges;
  std::vector<std::int64_t> start;
  std::unordered_map<std::int64_t, std::vector<std::int32_t>> cells;
  std::vector<double> cost;
  std::vector<std::int32_t> from;
  std::vector<std::uint32_t> seen;
  auto cellOf = [&](const Eigen::Vector3d& p) {
    std::array<std::int64_t, 3> c{};
    for (int k = 0; k < 3; ++k) c[std::size_t(k)] = std::clamp<std::int64_t>(std::int64_t(std::floor(p[k] / tolerance)), -(1 << 20), 1 << 20);
    return c;
  };
  auto key = [](std::int64_t x, std::int64_t y, std::int64_t z) {
    return ((x + (1 << 21)) << 44) | ((y + (1 << 21)) << 22) | (z + (1 << 21));
  };
  auto buildIndex = [&] {
    nv = complex.vertexSlots();
    domain.assign(std::size_t(nv), 0);
    edges.clear();
    for (std::int32_t t = 0; t < complex.tetSlots(); ++t) {
      if (!complex.tetAlive(t) || complex.isDummyTet(t) || complex.label(t) <= 0) continue;
      const Tet& q = complex.tet(t);
      for (int i = 0; i < 4; ++i) {
        domain[std::size_t(q[std::size_t(i)])] = 1;
        for (int j = i + 1; j < 4; ++j) {
          const auto e = std::minmax(q[std::size_t(i)], q[std::size_t(j)]);
          edges.push_back(e);
          edges.push_back({e.second, e.first});
        }
      }
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    start.assign(std::size_t(nv) + 1, 0);
    for (const auto& e : edges) ++start[std::size_t(e.first) + 1];
    for (std::size_t v = 1; v < start.size(); ++v) start[v] += start[v - 1];
    cells.clear();
    for (std::int32_t v = 0; v < nv; ++v)
      if (domain[std::size_t(v)]) {
        const auto c = cellOf(complex.position(v));
        cells[key(c[0], c[1], c[2])].push_back(v);
      }
    cost.assign(std::size_t(nv), 0.0);
    from.assign(std::size_t(nv), -1);
    seen.assign(std::size_t(nv), 0);
  };
  buildIndex();
  auto nearest = [&](const Eigen::Vector3d& p, std::size_t segment) {
    std::int32_t best = -1;
    double bestDistance = std::numeric_limits<double>::infinity();
    const auto c = cellOf(p);
    for (std::int64_t dz = -1; dz <= 1; ++dz)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dx = -1; dx <= 1; ++dx) {
          const auto it = cells.find(key(c[0] + dx, c[1] + dy, c[2] + dz));
          if (it == cells.end()) continue;
          for (std::int32_t v : it->second) {
            const double d = (complex.position(v) - p).squaredNorm();
            if (d < bestDistance || (d == bestDistance && v < best)) bestDistance = d, best = v;
          }
        }
    if (best < 0 || std::sqrt(bestDistance) > tolerance) {
      // Out of reach: the distance the message gives, from every vertex.
      for (std::int32_t v = 0; v < nv; ++v)
        if (domain[std::size_t(v)]) bestDistance = std::min(bestDistance, (complex.position(v) - p).squaredNorm());
      best = bestDistance < std::numeric_limits<double>::infinity() ? 0 : -1;
      char text[160];
      std::snprintf(text, sizeof text, " is %.4g mm from the mesh (more than %.4g mm)",
                    best < 0 ? std::numeric_limits<double>::infinity() : std::sqrt(bestDistance), tolerance);
      throw InputError(source, "segment " + std::to_string(segment + 1) + ": point " + formatPoint(p) + text);
    }
    return best;
  };

  // Shortest paths along the edges, each edge costing its length plus four
  // times the distances of its end points from the segment: the path hugs
  // it, through the vertices split onto it below rather than past them.
  std::uint32_t stamp = 0;
  auto path = [&](std::int32_t a, std::int32_t b, const FeatureSegment& s, std::size_t segment) {
    ++stamp;
    using Entry = std::pair<double, std::int32_t>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
    cost[std::size_t(a)] = 0.0;
    from[std::size_t(a)] = -1;
    seen[std::size_t(a)] = stamp;
    queue.push({0.0, a});
    while (!queue.empty()) {
      const auto [c, x] = queue.top();
      queue.pop();
      if (c > cost[std::size_t(x)]) continue;
      if (x == b) break;
      const double dx = distanceToSegment(s, complex.position(x));
      for (std::int64_t i = start[std::size_t(x)]; i < start[std::size_t(x) + 1]; ++i) {
        const std::int32_t y = edges[std::size_t(i)].second;
        const double next = c + (complex.position(y) - complex.position(x)).norm() +
                            4.0 * (dx + distanceToSegment(s, complex.position(y)));
        if (seen[std::size_t(y)] == stamp && next >= cost[std::size_t(y)]) continue;
        seen[std::size_t(y)] = stamp;
        cost[std::size_t(y)] = next;
        from[std::size_t(y)] = x;
        queue.push({next, y});
      }
    }
    if (seen[std::size_t(b)] != stamp)
      throw InputError(source, "segment " + std::to_string(segment + 1) + " joins parts of the mesh that no edge connects");
    std::vector<std::int32_t> out{b};
    while (out.back() != a) out.push_back(from[std::size_t(out.back())]);
    return out;
  };

  // Every path is found before anything is tagged: a refused file leaves the complex as it was.
  std::vector<std::vector<std::int32_t>> walks(segments.size());
  std::vector<std::int32_t> snapped(pointIds.size(), -1);
  auto findWalks = [&] {
    for (std::size_t s = 0; s < segments.size(); ++s) {
      const std::int32_t a = nearest(segments[s][0], s), b = nearest(segments[s][1], s);
      snapped[std::size_t(ends[s][0])] = a;
      snapped[std::size_t(ends[s][1])] = b;
      walks[s] = a != b ? path(a, b, segments[s], s) : std::vector<std::int32_t>{};
    }
  };
  findWalks();
  // The polyline is inserted by splits where the paths stray from it: the
  // vertices where a path crosses a 1-junction of the labels are corners
  // that will not move, and the others start off the line. The edges near
  // them are split where they come closest to the segment, and the paths
  // are found again through the new vertices (up to three rounds).
  for (int round = 0; round < 3 && splitCrossings(complex, segments, walks, tolerance) > 0; ++round) {
    buildIndex();
    findWalks();
  }
  FeatureEdges& features = complex.features();
  std::map<std::int32_t, std::int32_t> lineOfRoot;
  std::map<std::int32_t, std::vector<FeatureSegment>> geometry;
  for (std::size_t s = 0; s < segments.size(); ++s) geometry[joined.find(ends[s][0])].push_back(segments[s]);
  for (auto& [root, pieces] : geometry) lineOfRoot[root] = features.addLine(pieces);
  for (std::size_t s = 0; s < segments.size(); ++s) {
    const std::int32_t line = lineOfRoot[joined.find(ends[s][0])];
    for (std::size_t i = 0; i + 1 < walks[s].size(); ++i) features.tag(walks[s][i], walks[s][i + 1], line);
  }
  // Kinks of the input polylines (not of the paths, which zigzag along the
  // mesh edges) are corners.
  std::vector<std::vector<Eigen::Vector3d>> away(pointIds.size());
  for (std::size_t s = 0; s < segments.size(); ++s) {
    away[std::size_t(ends[s][0])].push_back(segments[s][1] - segments[s][0]);
    away[std::size_t(ends[s][1])].push_back(segments[s][0] - segments[s][1]);
  }
  const double straight = std::cos(angleDeg * M_PI / 180.0);
  for (std::size_t p = 0; p < away.size(); ++p)
    if (away[p].size() == 2 && !(-away[p][0].normalized().dot(away[p][1].normalized()) >= straight))
      features.setCorner(snapped[p]);
  return geometry.size();
}

double oneSidedLineDistance(const std::vector<FeatureSegment>& from, const std::vector<FeatureSegment>& to, double step) {
  double worst = 0.0;
  for (const FeatureSegment& s : from) {
    const int n = std::max(1, int(std::ceil((s[1] - s[0]).norm() / step)));
    for (int i = 0; i <= n; ++i) {
      const Eigen::Vector3d p = s[0] + (s[1] - s[0]) * (double(i) / n);
      double best = std::numeric_limits<double>::infinity();
      for (const FeatureSegment& t : to) best = std::min(best, distanceToSegment(t, p));
      worst = std::max(worst, best);
    }
  }
  return worst;
}

}  // namespace vox::remesh
