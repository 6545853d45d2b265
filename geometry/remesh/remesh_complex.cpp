#include "geometry/remesh/remesh_complex.h"

#include "geometry/cancellation.h"
#include "geometry/error.h"
#include "geometry/remesh/local_embedding.h"
#include "geometry/remesh/tet_shape.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <tuple>
#include <cmath>
#include <limits>
#include <numbers>

namespace vox::remesh {

void throwFlatTet(const std::string& source, std::size_t tet) {
  throw InputError(source, "tet " + std::to_string(tet) + " has zero volume (its four vertices are coplanar)");
}

void checkNoFlatTets(const TetMesh& mesh, const std::string& source) {
  for (std::size_t t = 0; t < mesh.tetCount(); ++t)
    if (!(std::abs(signedVolume(mesh.positions, mesh.tets[t])) > 0.0)) throwFlatTet(source, t);
}

RemeshComplex::RemeshComplex(const TetMesh& mesh, const std::string& source) {
  mesh.validate(source);
  throwIfCancelled();
  if (mesh.positions.size() >= std::size_t(std::numeric_limits<std::int32_t>::max() / 4) ||
      mesh.tets.size() >= std::size_t(std::numeric_limits<std::int32_t>::max() / 8))
    throw InputError(source, "is too large to remesh (more than 2^28 tets)");
  positions_ = mesh.positions;
  tets_ = mesh.tets;
  // Either orientation is accepted: negative tets are turned over; a tet
  // without volume is the input's fault.
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    if (mesh.labels[t] < 0) throw InputError(source, "tet " + std::to_string(t) + " has a negative label");
    const double v = signedVolume(mesh.positions, mesh.tets[t]);
    if (v < 0.0) std::swap(tets_[t][2], tets_[t][3]);
    else if (!(v > 0.0)) throwFlatTet(source, t);
  }

  labels_ = mesh.labels;
  neighbors_ = tetFaceAdjacency(tets_, std::int32_t(positions_.size()), source);
  checkLocalEmbedding(positions_, tets_, neighbors_, source);
  throwIfCancelled();
  // Edges met by more than two open facets: parts of the input touch along
  // them. Their end points are pinned, so the contact stays as it is.
  std::vector<std::pair<std::int32_t, std::int32_t>> openEdges;
  for (std::size_t t = 0; t < tets_.size(); ++t)
    for (int k = 0; k < 4; ++k)
      if (neighbors_[t][std::size_t(k)] == kNoFace) {
        const Tri f = tetFace(tets_[t], k);
        for (int i = 0; i < 3; ++i) openEdges.push_back(std::minmax(f[std::size_t(i)], f[std::size_t((i + 1) % 3)]));
      }
  sortCancellable(openEdges.begin(), openEdges.end());
  splitPinchedVertices();
  throwIfCancelled();
  pinned_.assign(positions_.size() + 1, 0);
  for (std::size_t v = 0; v < pinchOf_.size(); ++v)
    if (pinchOf_[v] >= 0) pinned_[v] = 1;
  for (std::size_t i = 0; i < openEdges.size();) {
    std::size_t j = i + 1;
    while (j < openEdges.size() && openEdges[j] == openEdges[i]) ++j;
    if (j - i > 2) pinned_[std::size_t(openEdges[i].first)] = pinned_[std::size_t(openEdges[i].second)] = 1;
    i = j;
  }

  // Join every open facet to the dummy vertex. Face k of a positive tet is
  // oriented outwards (tetFace), so (face, dummy) is positive "at infinity".
  dummy_ = std::int32_t(positions_.size());
  positions_.push_back(Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  const std::size_t domainTets = tets_.size();
  std::vector<Tet> cone;
  std::vector<std::int32_t> coneBase;  // 4 * tet + k of the facet each cone tet closes
  for (std::size_t t = 0; t < domainTets; ++t)
    for (int k = 0; k < 4; ++k)
      if (neighbors_[t][std::size_t(k)] == kNoFace) {
        const Tri f = tetFace(tets_[t], k);
        cone.push_back({f[0], f[1], f[2], dummy_});
        coneBase.push_back(std::int32_t(4 * t + std::size_t(k)));
      }
  throwIfCancelled();
  for (std::size_t c = 0; c < cone.size(); ++c) {
    const std::int32_t base = coneBase[c];
    tets_.push_back(cone[c]);
    labels_.push_back(mesh.labels[std::size_t(base / 4)] == kBackgroundLabel ? kDummyLabel : kBackgroundLabel);
    neighbors_.push_back({kNoFace, kNoFace, kNoFace, base});
    neighbors_[std::size_t(base / 4)][std::size_t(base % 4)] = 4 * std::int32_t(domainTets + c) + 3;
  }
  glueCone(domainTets, source);
  throwIfCancelled();

  vertexTet_.assign(positions_.size(), -1);
  std::vector<std::int32_t> incidence(positions_.size(), 0);
  for (std::size_t t = 0; t < tets_.size(); ++t)
    for (std::int32_t v : tets_[t]) {
      if (vertexTet_[std::size_t(v)] < 0) vertexTet_[std::size_t(v)] = std::int32_t(t);
      ++incidence[std::size_t(v)];
    }
  for (std::int32_t v = 0; v < std::int32_t(positions_.size()); ++v)
    if (vertexTet_[std::size_t(v)] < 0 && v != dummy_) freeVertices_.push_back(v);
  std::reverse(freeVertices_.begin(), freeVertices_.end());
  throwIfCancelled();

  // The operations find a vertex's tets by walking through its faces, and an
  // edge's tets by walking around it: the first walk must reach all of them,
  // and the second must close up after all of them (one cycle, as the
  // faces of the extended complex are each in two tets). Edges to the dummy
  // vertex at a pinned vertex may close up in several cycles (its open facets
  // form several fans); no operation walks around them.
  std::vector<std::int32_t> star;
  std::vector<std::pair<std::int32_t, std::int32_t>> edgeTets;  // (other end point, tet)
  for (std::int32_t v = 0; v < std::int32_t(positions_.size()); ++v) {
    throwIfCancelled();  // seconds on a mesh of millions of tets
    if (v == dummy_ || vertexTet_[std::size_t(v)] < 0) continue;
    incidentTets(v, star);
    if (std::int32_t(star.size()) != incidence[std::size_t(v)])
      throw InputError(source, "vertex " + std::to_string(v) + " is non-manifold (its tets are not connected through faces)");
    edgeTets.clear();
    for (std::int32_t t : star)
      for (std::int32_t w : tets_[std::size_t(t)])
        if (w > v && !(w == dummy_ && isPinned(v))) edgeTets.push_back({w, t});
    std::sort(edgeTets.begin(), edgeTets.end());
    for (std::size_t i = 0; i < edgeTets.size();) {
      std::size_t j = i + 1;
      while (j < edgeTets.size() && edgeTets[j].first == edgeTets[i].first) ++j;
      const std::int32_t missed = tetOffEdgeCycle(v, edgeTets[i].first, edgeTets[i].second, j - i, star);
      if (missed >= 0) {
        // Named by the input tet: a dummy tet by the domain tet it closes.
        const std::int32_t t = std::size_t(missed) < domainTets ? missed : neighbors_[std::size_t(missed)][3] >> 2;
        auto original = [&](std::int32_t x) { return pinchOf(x) >= 0 ? pinchOf(x) : x; };
        Tet q = tets_[std::size_t(t)];
        for (std::int32_t& x : q) x = original(x);
        throw InputError(source, describeTet(std::size_t(t), q) + " is not reached by the walk around edge (" +
                                     std::to_string(original(v)) + ", " +
                                     (edgeTets[i].first == dummy_ ? std::string("outside") : std::to_string(original(edgeTets[i].first))) +
                                     "): the tets around that edge form more than one cycle");
      }
      i = j;
    }
  }
}

std::int32_t RemeshComplex::tetOffEdgeCycle(std::int32_t a, std::int32_t b, std::int32_t t, std::size_t count,
                                            const std::vector<std::int32_t>& starOfA) const {
  // The walk of edgeRing, stopped after `count` steps.
  std::int32_t p = -1, r = -1;
  for (std::int32_t v : tets_[std::size_t(t)])
    if (v != a && v != b) (p < 0 ? p : r) = v;
  std::vector<std::int32_t> cycle;
  std::int32_t cur = t;
  bool closed = false;
  while (cycle.size() < count) {
    cycle.push_back(cur);
    const std::int32_t next = neighbor(cur, localIndex(cur, p));
    if (next == t) {
      closed = true;
      break;
    }
    std::int32_t s = -1;
    for (std::int32_t v : tets_[std::size_t(next)])
      if (v != a && v != b && v != r) s = v;
    if (s < 0 || localIndex(next, a) < 0 || localIndex(next, b) < 0) break;
    cur = next;
    p = r;
    r = s;
  }
  if (closed && cycle.size() == count) return -1;
  // The smallest tet of the edge that the walk missed, or where it stopped.
  std::sort(cycle.begin(), cycle.end());
  std::int32_t missed = -1;
  for (std::int32_t q : starOfA)
    if (localIndex(q, b) >= 0 && !std::binary_search(cycle.begin(), cycle.end(), q) && (missed < 0 || q < missed))
      missed = q;
  return missed >= 0 ? missed : cur;
}

void RemeshComplex::splitPinchedVertices() {
  // The tets around each vertex, grouped by the faces through it: two parts
  // of the mesh touching at a vertex (or along an edge, at its end points)
  // form several groups. Each further group gets a copy of the vertex at the
  // same place, so every star is connected through faces; toTetMesh merges
  // the copies again, and they are pinned, so they stay together.
  // Only a vertex on an open facet can be pinched in a mesh whose tets do not
  // overlap (elsewhere each group's link would be a closed surface around it).
  const std::size_t nv = positions_.size(), nt = tets_.size();
  std::vector<std::uint8_t> open(nv, 0);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 4; ++k)
      if (neighbors_[t][std::size_t(k)] == kNoFace)
        for (int i = 0; i < 4; ++i)
          if (i != k) open[std::size_t(tets_[t][std::size_t(i)])] = 1;
  throwIfCancelled();
  std::vector<std::int64_t> first(nv + 1, 0);
  for (const Tet& q : tets_)
    for (std::int32_t v : q) first[std::size_t(v) + 1] += open[std::size_t(v)];
  for (std::size_t v = 0; v < nv; ++v) first[v + 1] += first[v];
  std::vector<std::int32_t> star(static_cast<std::size_t>(first[nv]));
  {
    std::vector<std::int64_t> fill(first.begin(), first.end() - 1);
    for (std::size_t t = 0; t < nt; ++t)
      for (std::int32_t v : tets_[t])
        if (open[std::size_t(v)]) star[std::size_t(fill[std::size_t(v)]++)] = std::int32_t(t);
  }
  throwIfCancelled();
  pinchOf_.assign(nv, -1);
  std::vector<std::uint32_t> seen(nt, 0);
  std::uint32_t stamp = 0;
  std::vector<std::int32_t> queue;
  for (std::size_t v = 0; v < nv; ++v) {
    if (v % 65536 == 0) throwIfCancelled();
    const std::int64_t b = first[v], e = first[v + 1];
    if (e - b < 2) continue;
    ++stamp;
    int groups = 0;
    for (std::int64_t i = b; i < e; ++i) {
      const std::int32_t t0 = star[std::size_t(i)];
      if (seen[std::size_t(t0)] == stamp) continue;
      // A further group: its tets take a copy of v.
      std::int32_t w = std::int32_t(v);
      if (groups++ > 0) {
        w = std::int32_t(positions_.size());
        positions_.push_back(positions_[v]);
        pinchOf_.push_back(std::int32_t(v));
        pinchOf_[v] = std::int32_t(v);
        hasPinches_ = true;
      }
      queue.assign(1, t0);
      seen[std::size_t(t0)] = stamp;
      for (std::size_t j = 0; j < queue.size(); ++j) {
        const std::int32_t t = queue[j];
        Tet& q = tets_[std::size_t(t)];
        for (int k = 0; k < 4; ++k) {
          if (q[std::size_t(k)] == std::int32_t(v)) continue;
          const std::int32_t code = neighbors_[std::size_t(t)][std::size_t(k)];
          if (code == kNoFace || seen[std::size_t(code >> 2)] == stamp) continue;
          seen[std::size_t(code >> 2)] = stamp;
          queue.push_back(code >> 2);
        }
      }
      if (w != std::int32_t(v))
        for (std::int32_t t : queue)
          for (std::int32_t& x : tets_[std::size_t(t)])
            if (x == std::int32_t(v)) x = w;
    }
  }
}

void RemeshComplex::glueCone(std::size_t domainTets, const std::string& source) {
  // Face k < 3 of a cone tet (f0, f1, f2, dummy) holds the facet's edge
  // opposite f_k and the dummy vertex. Along an edge of a closed manifold
  // boundary two facets meet and their cone tets are glued. Where the
  // boundary is pinched along an edge (2m facets), the facets are ordered by
  // angle around the edge and each is glued to its neighbour on the side
  // away from the domain: the cone tets around the edge then close up like
  // the outside does, and the edge's end points are pinned.
  struct Entry {
    std::int32_t lo, hi;  // the edge
    std::int32_t face;    // 4 * cone tet + k
  };
  std::vector<Entry> entries;
  for (std::size_t t = domainTets; t < tets_.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::int32_t x = tets_[t][std::size_t((k + 1) % 3)], y = tets_[t][std::size_t((k + 2) % 3)];
      entries.push_back({std::min(x, y), std::max(x, y), std::int32_t(4 * t + std::size_t(k))});
    }
  sortCancellable(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return std::tie(a.lo, a.hi, a.face) < std::tie(b.lo, b.hi, b.face);
  });
  auto glueFaces = [&](std::int32_t f, std::int32_t g) {
    neighbors_[std::size_t(f >> 2)][std::size_t(f & 3)] = g;
    neighbors_[std::size_t(g >> 2)][std::size_t(g & 3)] = f;
  };
  auto edgeName = [&](std::int32_t x, std::int32_t y) {
    auto original = [&](std::int32_t v) { return pinchOf(v) >= 0 ? pinchOf(v) : v; };
    return "(" + std::to_string(original(x)) + ", " + std::to_string(original(y)) + ")";
  };
  struct Around {
    double angle;
    bool domainAhead;  // the domain lies at larger angles
    std::int32_t face;
  };
  std::vector<Around> around;
  for (std::size_t i = 0; i < entries.size();) {
    std::size_t j = i + 1;
    while (j < entries.size() && entries[j].lo == entries[i].lo && entries[j].hi == entries[i].hi) ++j;
    const std::int32_t x = entries[i].lo, y = entries[i].hi;
    if (j - i == 2) {
      glueFaces(entries[i].face, entries[i + 1].face);
    } else {
      if ((j - i) % 2 != 0)
        throw InputError(source, "the outer boundary is not closed at edge " + edgeName(x, y) + " (" +
                                     std::to_string(j - i) + " open facets meet there)");
      pinned_[std::size_t(x)] = pinned_[std::size_t(y)] = 1;
      const Eigen::Vector3d px = positions_[std::size_t(x)];
      const Eigen::Vector3d axis = (positions_[std::size_t(y)] - px).normalized();
      Eigen::Vector3d e1 = axis.unitOrthogonal();
      const Eigen::Vector3d e2 = axis.cross(e1);
      auto angleOf = [&](std::int32_t v) {
        const Eigen::Vector3d d = positions_[std::size_t(v)] - px;
        return std::atan2(d.dot(e2), d.dot(e1));
      };
      around.clear();
      for (std::size_t n = i; n < j; ++n) {
        const std::int32_t c = entries[n].face >> 2, k = entries[n].face & 3;
        const std::int32_t z = tets_[std::size_t(c)][std::size_t(k)];
        const std::int32_t base = neighbors_[std::size_t(c)][3];
        const std::int32_t q = tets_[std::size_t(base >> 2)][std::size_t(base & 3)];
        const double a = angleOf(z);
        double d = angleOf(q) - a;
        if (d > std::numbers::pi) d -= 2 * std::numbers::pi;
        if (d <= -std::numbers::pi) d += 2 * std::numbers::pi;
        around.push_back({a, d > 0.0, entries[n].face});
      }
      std::sort(around.begin(), around.end(), [](const Around& a, const Around& b) {
        return a.angle < b.angle || (a.angle == b.angle && a.face < b.face);
      });
      // Outside lies between a facet with the domain behind it and the next
      // one, which has the domain ahead.
      const std::size_t m = around.size();
      for (std::size_t n = 0; n < m; ++n) {
        const Around& a = around[n];
        const Around& b = around[(n + 1) % m];
        if (a.domainAhead == b.domainAhead)
          throw InputError(source, "the tets around edge " + edgeName(x, y) + " overlap");
        if (!a.domainAhead) glueFaces(a.face, b.face);
      }
    }
    i = j;
  }
  // A boundary vertex whose open facets form more than one fan (two parts
  // touching at a point from outside, or the end of a pinched edge) is
  // pinned: it is where the outer boundary is not a surface.
  std::vector<std::pair<std::int32_t, std::int32_t>> fans;  // (vertex, cone tet)
  for (std::size_t t = domainTets; t < tets_.size(); ++t)
    for (int k = 0; k < 3; ++k) fans.push_back({tets_[t][std::size_t(k)], std::int32_t(t)});
  sortCancellable(fans.begin(), fans.end());
  std::vector<std::int32_t> queue;
  std::vector<std::uint32_t> seen(tets_.size(), 0);
  std::uint32_t stamp = 0;
  for (std::size_t i = 0; i < fans.size();) {
    std::size_t j = i + 1;
    while (j < fans.size() && fans[j].first == fans[i].first) ++j;
    const std::int32_t v = fans[i].first;
    ++stamp;
    queue.assign(1, fans[i].second);
    seen[std::size_t(fans[i].second)] = stamp;
    for (std::size_t n = 0; n < queue.size(); ++n) {
      const Tet& q = tets_[std::size_t(queue[n])];
      for (int k = 0; k < 3; ++k) {  // faces holding the dummy vertex
        if (q[std::size_t(k)] == v) continue;
        const std::int32_t c = neighbors_[std::size_t(queue[n])][std::size_t(k)] >> 2;
        if (seen[std::size_t(c)] == stamp) continue;
        seen[std::size_t(c)] = stamp;
        queue.push_back(c);
      }
    }
    if (queue.size() != j - i) pinned_[std::size_t(v)] = 1;
    i = j;
  }
}

TetMesh RemeshComplex::toTetMesh(bool keepImaginary, std::vector<TaggedEdge>* features) const {
  TetMesh out;
  std::vector<std::int32_t> remap(positions_.size(), -1);
  auto kept = [&](std::size_t t) {
    if (tets_[t][0] < 0) return false;
    if (labels_[t] > 0) return true;
    return keepImaginary && labels_[t] == kBackgroundLabel && !isDummyTet(std::int32_t(t));
  };
  // Copies of a pinched vertex are written as the vertex itself.
  auto original = [&](std::int32_t v) { return pinchOf(v) >= 0 ? pinchOf(v) : v; };
  for (std::size_t t = 0; t < tets_.size(); ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    if (kept(t))
      for (std::int32_t v : tets_[t]) remap[std::size_t(original(v))] = 0;
  }
  std::int32_t next = 0;
  for (std::size_t v = 0; v < positions_.size(); ++v)
    if (remap[v] == 0) {
      remap[v] = next++;
      out.positions.push_back(positions_[v]);
    }
  throwIfCancelled();
  for (std::size_t t = 0; t < tets_.size(); ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    if (!kept(t)) continue;
    Tet q = tets_[t];
    for (auto& v : q) v = remap[std::size_t(original(v))];
    out.tets.push_back(q);
    out.labels.push_back(labels_[t]);
  }
  if (features) {
    features->clear();
    for (TaggedEdge e : features_.list()) {
      const std::int32_t a = remap[std::size_t(original(e.a))], b = remap[std::size_t(original(e.b))];
      if (a < 0 || b < 0 || a == b) continue;
      features->push_back({std::min(a, b), std::max(a, b), e.line});
    }
  }
  return out;
}

std::uint32_t StarWalker::nextStamp(std::size_t tetSlots) {
  if (mark_.size() < tetSlots) mark_.resize(tetSlots + tetSlots / 4 + 16, 0);
  if (++stamp_ == 0) {
    std::fill(mark_.begin(), mark_.end(), 0);
    stamp_ = 1;
  }
  return stamp_;
}

void StarWalker::incidentTets(const RemeshComplex& complex, std::int32_t v, std::vector<std::int32_t>& out) {
  out.clear();
  const std::uint32_t s = nextStamp(std::size_t(complex.tetSlots()));
  const std::int32_t start = complex.anyTet(v);
  out.push_back(start);
  mark_[std::size_t(start)] = s;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const std::int32_t t = out[i];
    const Tet& q = complex.tet(t);
    for (int k = 0; k < 4; ++k) {
      if (q[std::size_t(k)] == v) continue;
      const std::int32_t n = complex.neighbor(t, k);
      if (mark_[std::size_t(n)] == s) continue;
      mark_[std::size_t(n)] = s;
      out.push_back(n);
    }
  }
}

std::int32_t StarWalker::findEdgeTet(const RemeshComplex& complex, std::int32_t a, std::int32_t b) {
  // Walk a's star, stopping at the first tet that also holds b.
  queue_.clear();
  const std::uint32_t s = nextStamp(std::size_t(complex.tetSlots()));
  const std::int32_t start = complex.anyTet(a);
  queue_.push_back(start);
  mark_[std::size_t(start)] = s;
  for (std::size_t i = 0; i < queue_.size(); ++i) {
    const std::int32_t t = queue_[i];
    const Tet& q = complex.tet(t);
    if (q[0] == b || q[1] == b || q[2] == b || q[3] == b) return t;
    for (int k = 0; k < 4; ++k) {
      if (q[std::size_t(k)] == a) continue;
      const std::int32_t n = complex.neighbor(t, k);
      if (mark_[std::size_t(n)] == s) continue;
      mark_[std::size_t(n)] = s;
      queue_.push_back(n);
    }
  }
  return -1;
}

void RemeshComplex::starVertices(const std::vector<std::int32_t>& tets, std::int32_t except,
                                 std::vector<std::int32_t>& out, std::int32_t above) const {
  out.clear();
  for (std::int32_t t : tets)
    for (std::int32_t w : tets_[std::size_t(t)])
      if (w > above && w != except && w != dummy_) out.push_back(w);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

void RemeshComplex::edgeRing(std::int32_t a, std::int32_t b, std::int32_t t, EdgeRing& out) const {
  out.a = a;
  out.b = b;
  out.tets.clear();
  out.ring.clear();
  const Tet& q0 = tets_[std::size_t(t)];
  std::int32_t p = -1, r = -1;
  for (std::int32_t v : q0)
    if (v != a && v != b) (p < 0 ? p : r) = v;
  std::int32_t cur = t;
  // No edge has more tets than the complex: a walk that has not closed by
  // then never will (a corrupt complex), and must not spin.
  for (std::int32_t step = 0; step < tetSlots(); ++step) {
    out.tets.push_back(cur);
    out.ring.push_back(p);
    // Step across the face opposite p; it holds a, b and r.
    const int kp = localIndex(cur, p);
    const std::int32_t next = neighbor(cur, kp);
    if (next == t) return;
    std::int32_t s = -1;
    for (std::int32_t v : tets_[std::size_t(next)])
      if (v != a && v != b && v != r) s = v;
    cur = next;
    p = r;
    r = s;
  }
  throw RuntimeFailure("remesh: the tets around edge (" + std::to_string(a) + ", " + std::to_string(b) +
                       ") do not close up (corrupt complex)");
}

std::int32_t RemeshComplex::addVertex(const Eigen::Vector3d& p) {
  if (!freeVertices_.empty()) {
    const std::int32_t v = freeVertices_.back();
    freeVertices_.pop_back();
    positions_[std::size_t(v)] = p;
    return v;
  }
  positions_.push_back(p);
  vertexTet_.push_back(-1);
  return std::int32_t(positions_.size() - 1);
}

void RemeshComplex::removeVertex(std::int32_t v) {
  vertexTet_[std::size_t(v)] = -1;
  freeVertices_.push_back(v);
}

std::int32_t RemeshComplex::addTet(const Tet& q, std::int32_t label) {
  if (!freeTets_.empty()) {
    const std::int32_t t = freeTets_.back();
    freeTets_.pop_back();
    tets_[std::size_t(t)] = q;
    labels_[std::size_t(t)] = label;
    return t;
  }
  tets_.push_back(q);
  labels_.push_back(label);
  neighbors_.push_back({kNoFace, kNoFace, kNoFace, kNoFace});
  return std::int32_t(tets_.size() - 1);
}

void RemeshComplex::removeTet(std::int32_t t) {
  tets_[std::size_t(t)] = {-1, -1, -1, -1};
  neighbors_[std::size_t(t)] = {kNoFace, kNoFace, kNoFace, kNoFace};
  freeTets_.push_back(t);
}

void RemeshComplex::replaceTets(const std::vector<std::int32_t>& removed, const std::vector<Tet>& added,
                                const std::vector<std::int32_t>& addedLabels, std::vector<std::int32_t>& out) {
  struct OpenFace {
    std::array<std::int32_t, 3> key;
    std::int32_t code;  // the face it must be glued to (outside the cavity), or an added face
    bool matched = false;
  };
  auto sortedFace = [](const Tet& q, int k) {
    std::array<std::int32_t, 3> f{};
    int n = 0;
    for (int i = 0; i < 4; ++i)
      if (i != k) f[std::size_t(n++)] = q[std::size_t(i)];
    std::sort(f.begin(), f.end());
    return f;
  };
  thread_local std::vector<OpenFace> boundary;
  boundary.clear();
  for (std::int32_t t : removed)
    for (int k = 0; k < 4; ++k) {
      const std::int32_t n = neighbor(t, k);
      if (std::find(removed.begin(), removed.end(), n) == removed.end())
        boundary.push_back({sortedFace(tets_[std::size_t(t)], k), encodedNeighbor(t, k)});
    }
  for (std::int32_t t : removed) removeTet(t);
  out.clear();
  for (std::size_t i = 0; i < added.size(); ++i) out.push_back(addTet(added[i], addedLabels[i]));
  thread_local std::vector<OpenFace> inner;
  inner.clear();
  for (std::int32_t t : out)
    for (int k = 0; k < 4; ++k) {
      const auto key = sortedFace(tets_[std::size_t(t)], k);
      bool glued = false;
      for (OpenFace& b : boundary)
        if (!b.matched && b.key == key) {
          b.matched = true;
          setEncodedNeighbor(t, k, b.code);
          setEncodedNeighbor(b.code >> 2, b.code & 3, 4 * t + k);
          glued = true;
          break;
        }
      for (std::size_t j = 0; !glued && j < inner.size(); ++j)
        if (!inner[j].matched && inner[j].key == key) {
          inner[j].matched = true;
          glue(t, k, inner[j].code >> 2, inner[j].code & 3);
          glued = true;
        }
      if (!glued) inner.push_back({key, 4 * t + k});
    }
  for (const OpenFace& f : inner)
    if (!f.matched) throw RuntimeFailure("remesh: new tets do not fill the cavity they replace");
  for (const OpenFace& f : boundary)
    if (!f.matched) throw RuntimeFailure("remesh: new tets leave a face of the cavity open");
  for (std::int32_t t : out)
    for (std::int32_t v : tets_[std::size_t(t)]) vertexTet_[std::size_t(v)] = t;
}

std::string RemeshComplex::checkConsistency(bool geometry) const {
  auto sortedFace = [&](std::int32_t t, int k) {
    std::array<std::int32_t, 3> f{};
    int n = 0;
    for (int i = 0; i < 4; ++i)
      if (i != k) f[std::size_t(n++)] = tets_[std::size_t(t)][std::size_t(i)];
    std::sort(f.begin(), f.end());
    return f;
  };
  for (std::int32_t t = 0; t < tetSlots(); ++t) {
    if (!tetAlive(t)) continue;
    const Tet& q = tets_[std::size_t(t)];
    for (int k = 0; k < 4; ++k) {
      if (q[std::size_t(k)] < 0 || q[std::size_t(k)] >= vertexSlots() || !vertexAlive(q[std::size_t(k)]))
        return "tet " + std::to_string(t) + " uses a removed vertex";
      for (int m = 0; m < k; ++m)
        if (q[std::size_t(m)] == q[std::size_t(k)]) return "tet " + std::to_string(t) + " repeats a vertex";
      const std::int32_t code = neighbors_[std::size_t(t)][std::size_t(k)];
      if (code < 0) return "tet " + std::to_string(t) + " has an open face";
      const std::int32_t n = code >> 2;
      const int kn = code & 3;
      if (!tetAlive(n)) return "tet " + std::to_string(t) + " neighbours a removed tet";
      if (neighbors_[std::size_t(n)][std::size_t(kn)] != 4 * t + k)
        return "adjacency of tets " + std::to_string(t) + " and " + std::to_string(n) + " is not symmetric";
      if (sortedFace(t, k) != sortedFace(n, kn))
        return "tets " + std::to_string(t) + " and " + std::to_string(n) + " are glued along different faces";
    }
    if (geometry && !isDummyTet(t) && !(volume(t) > 0.0))
      return "tet " + std::to_string(t) + " is inverted or flat (volume " + std::to_string(volume(t)) + ")";
  }
  for (std::int32_t v = 0; v < vertexSlots(); ++v) {
    if (!vertexAlive(v)) continue;
    const std::int32_t t = vertexTet_[std::size_t(v)];
    if (t < 0 || t >= tetSlots() || !tetAlive(t) || localIndex(t, v) < 0)
      return "vertex " + std::to_string(v) + " points to a tet that does not hold it";
  }
  return {};
}

double RemeshComplex::minDihedralCosineOf(std::int32_t t) const {
  const Tet& q = tets_[std::size_t(t)];
  return minDihedralCosine(positions_[std::size_t(q[0])], positions_[std::size_t(q[1])], positions_[std::size_t(q[2])],
                           positions_[std::size_t(q[3])]);
}

double RemeshComplex::worstDihedralCosineOf(const std::vector<std::int32_t>& tets) const {
  double worst = -1.0;
  for (std::int32_t t : tets)
    if (!isDummyTet(t)) worst = std::max(worst, minDihedralCosineOf(t));
  return worst;
}

namespace {
// Interleaves the low 21 bits of x, y and z.
std::uint64_t morton3(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  auto spread = [](std::uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
  };
  return spread(x) | spread(y) << 1 | spread(z) << 2;
}
}  // namespace

void RemeshComplex::reorderForLocality() {
  const std::size_t nv = positions_.size(), nt = tets_.size();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t v = 0; v < nv; ++v)
    if (vertexTet_[v] >= 0 && std::int32_t(v) != dummy_) {
      lo = lo.cwiseMin(positions_[v]);
      hi = hi.cwiseMax(positions_[v]);
    }
  const double extent = std::max((hi - lo).maxCoeff(), 1e-300);
  std::vector<std::pair<std::uint64_t, std::int32_t>> keys;
  keys.reserve(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    if (vertexTet_[v] < 0 && std::int32_t(v) != dummy_) continue;
    std::uint64_t key = std::numeric_limits<std::uint64_t>::max();  // the dummy vertex last
    if (std::int32_t(v) != dummy_) {
      const Eigen::Vector3d q = (positions_[v] - lo) / extent * double((1 << 21) - 1);
      key = morton3(std::uint32_t(q[0]), std::uint32_t(q[1]), std::uint32_t(q[2]));
    }
    keys.push_back({key, std::int32_t(v)});
  }
  sortCancellable(keys.begin(), keys.end());
  std::vector<std::int32_t> vmap(nv, -1);
  for (std::size_t i = 0; i < keys.size(); ++i) vmap[std::size_t(keys[i].second)] = std::int32_t(i);

  std::vector<std::pair<std::int32_t, std::int32_t>> tetKeys;
  tetKeys.reserve(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    if (tets_[t][0] < 0) continue;
    std::int32_t m = std::numeric_limits<std::int32_t>::max();
    for (std::int32_t v : tets_[t]) m = std::min(m, vmap[std::size_t(v)]);
    tetKeys.push_back({m, std::int32_t(t)});
  }
  sortCancellable(tetKeys.begin(), tetKeys.end());
  std::vector<std::int32_t> tmap(nt, -1);
  for (std::size_t i = 0; i < tetKeys.size(); ++i) tmap[std::size_t(tetKeys[i].second)] = std::int32_t(i);

  // One array at a time, each freed as its replacement takes over: the
  // peak is the complex plus the maps and one array.
  auto permuteVertices = [&](auto& data, auto missing, auto map) {
    std::remove_reference_t<decltype(data)> out(keys.size(), missing);
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const std::size_t v = std::size_t(keys[i].second);
      if (v < data.size()) out[i] = map(data[v]);
    }
    data = std::move(out);
    throwIfCancelled();
  };
  permuteVertices(positions_, Eigen::Vector3d::Zero().eval(), [](const Eigen::Vector3d& p) { return p; });
  permuteVertices(vertexTet_, std::int32_t(-1),
                  [&](std::int32_t t) { return t < 0 ? -1 : tmap[std::size_t(t)]; });
  permuteVertices(pinned_, std::uint8_t(0), [](std::uint8_t x) { return x; });
  if (!pinchOf_.empty())
    permuteVertices(pinchOf_, std::int32_t(-1),
                    [&](std::int32_t w) { return w < 0 ? -1 : vmap[std::size_t(w)]; });
  auto permuteTets = [&](auto& data, auto map) {
    std::remove_reference_t<decltype(data)> out(tetKeys.size());
    for (std::size_t i = 0; i < tetKeys.size(); ++i) out[i] = map(data[std::size_t(tetKeys[i].second)]);
    data = std::move(out);
    throwIfCancelled();
  };
  permuteTets(tets_, [&](const Tet& q) {
    Tet r;
    for (int k = 0; k < 4; ++k) r[std::size_t(k)] = vmap[std::size_t(q[std::size_t(k)])];
    return r;
  });
  permuteTets(labels_, [](std::int32_t l) { return l; });
  permuteTets(neighbors_, [&](const std::array<std::int32_t, 4>& n) {
    std::array<std::int32_t, 4> r;
    for (int k = 0; k < 4; ++k)
      r[std::size_t(k)] = n[std::size_t(k)] < 0 ? n[std::size_t(k)] : 4 * tmap[std::size_t(n[std::size_t(k)] >> 2)] + (n[std::size_t(k)] & 3);
    return r;
  });
  freeVertices_.clear();
  freeVertices_.shrink_to_fit();
  freeTets_.clear();
  freeTets_.shrink_to_fit();
  dummy_ = vmap[std::size_t(dummy_)];
  if (!features_.empty()) features_.renumber(vmap);
}

}  // namespace vox::remesh
