#include "geometry/remesh/local_embedding.h"

#include "geometry/cancellation.h"
#include "geometry/error.h"
#include "geometry/remesh/face_adjacency.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace vox::remesh {

namespace {

// Angles summed over a star are compared with a turn (a sphere) with this
// much slack: rounding of a few hundred atan2 is far below it, and a tet
// overlapping its neighbours by less covers no direction twice that matters
// to the remesher (its walks are combinatorial; the slack only keeps a slit,
// whose two sides meet at exactly one turn, from being refused by rounding).
constexpr double kAngleSlack = 1e-6;
constexpr double kTurn = 2 * std::numbers::pi;
// A direction counts as strictly on one side of a plane through the vertex
// when it is this far from it (relative to the distances involved): two sides
// of a slit, whose facets coincide, are not taken for an overlap by rounding.
constexpr double kSideSlack = 1e-9;

// Interior dihedral angle of tet (p_i, p_j, p_k, p_l) at edge (i, j): the
// angle between the half-planes through the edge towards k and towards l,
// from atan2 of |e| |det(e, a, b)| and (e x a).(e x b), accurate for flat and
// for obtuse angles alike.
double dihedralAngle(const Eigen::Vector3d& pi, const Eigen::Vector3d& pj, const Eigen::Vector3d& pk,
                     const Eigen::Vector3d& pl) {
  const Eigen::Vector3d e = pj - pi, a = pk - pi, b = pl - pi;
  return std::atan2(e.norm() * std::abs(e.dot(a.cross(b))), e.cross(a).dot(e.cross(b)));
}

// Solid angle of tet (p, a, b, c) at p (Van Oosterom and Strackee 1983).
double solidAngle(const Eigen::Vector3d& p, const Eigen::Vector3d& pa, const Eigen::Vector3d& pb,
                  const Eigen::Vector3d& pc) {
  const Eigen::Vector3d a = pa - p, b = pb - p, c = pc - p;
  const double la = a.norm(), lb = b.norm(), lc = c.norm();
  const double det = std::abs(a.dot(b.cross(c)));
  return 2.0 * std::atan2(det, la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la);
}

// Whether triangle g is triangle f with the same orientation (a rotation of
// its vertices).
bool sameOrientation(const Tri& f, const Tri& g) {
  for (int r = 0; r < 3; ++r)
    if (g[0] == f[std::size_t(r)] && g[1] == f[std::size_t((r + 1) % 3)] && g[2] == f[std::size_t((r + 2) % 3)])
      return true;
  return false;
}

// The tets of `group` (all holding `shared`, one or two vertices) split into
// the classes connected through the faces that hold `shared`; returns a tet of
// the smallest class (the smallest index on ties): where a star covers some
// direction twice, the part that intrudes is the small one.
std::int32_t smallestFan(const std::vector<Tet>& tets, const std::vector<std::array<std::int32_t, 4>>& neighbors,
                         std::vector<std::int32_t> group, std::initializer_list<std::int32_t> shared) {
  std::sort(group.begin(), group.end());
  std::vector<int> fan(group.size(), -1);
  std::vector<std::size_t> size;
  std::vector<std::int32_t> queue;
  for (std::size_t s = 0; s < group.size(); ++s) {
    if (fan[s] >= 0) continue;
    const int id = int(size.size());
    fan[s] = id;
    queue.assign(1, group[s]);
    for (std::size_t i = 0; i < queue.size(); ++i) {
      const Tet& q = tets[std::size_t(queue[i])];
      for (int k = 0; k < 4; ++k) {
        if (std::find(shared.begin(), shared.end(), q[std::size_t(k)]) != shared.end()) continue;
        const std::int32_t code = neighbors[std::size_t(queue[i])][std::size_t(k)];
        if (code == kNoFace) continue;
        const auto it = std::lower_bound(group.begin(), group.end(), code >> 2);
        if (it == group.end() || *it != code >> 2) continue;
        const std::size_t n = std::size_t(it - group.begin());
        if (fan[n] >= 0) continue;
        fan[n] = id;
        queue.push_back(code >> 2);
      }
    }
    size.push_back(queue.size());
  }
  std::size_t best = 0;
  for (std::size_t s = 1; s < group.size(); ++s)
    if (size[std::size_t(fan[s])] < size[std::size_t(fan[best])]) best = s;
  return group[best];
}

// Whether the great-circle arcs (a, b) and (c, d) of the unit sphere (each
// shorter than half a turn) cross at a point inside both: each pair of end
// points strictly on either side of the other arc's great circle, and the
// two circles' common point on the same side for both (the arcs cannot
// cross at antipodal points).
bool arcsCross(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  const Eigen::Vector3d n1 = a.cross(b), n2 = c.cross(d);
  const double s1 = n1.dot(c), s2 = n1.dot(d), s3 = n2.dot(a), s4 = n2.dot(b);
  auto apart = [](double x, double y) { return (x < -kSideSlack && y > kSideSlack) || (x > kSideSlack && y < -kSideSlack); };
  if (!apart(s1, s2) || !apart(s3, s4)) return false;
  const Eigen::Vector3d x = n1.cross(n2);
  return (x.dot(a + b) > 0.0) == (x.dot(c + d) > 0.0);
}

// Whether point p (at distance about `reach` from v) lies strictly inside the
// cone of positive tet q at its vertex v: behind the three faces of q through
// v, each by more than the slack.
bool insideCone(const std::vector<Eigen::Vector3d>& positions, const Tet& q, std::int32_t v, const Eigen::Vector3d& p,
                double reach) {
  for (int k = 0; k < 4; ++k) {
    if (q[std::size_t(k)] == v) continue;
    const Tri f = tetFace(q, k);
    const Eigen::Vector3d& o = positions[std::size_t(f[0])];
    const Eigen::Vector3d n = (positions[std::size_t(f[1])] - o).cross(positions[std::size_t(f[2])] - o).normalized();
    if (!(n.dot(p - o) < -kSideSlack * reach)) return false;
  }
  return true;
}

}  // namespace

void checkLocalEmbedding(const std::vector<Eigen::Vector3d>& positions, const std::vector<Tet>& tets,
                         const std::vector<std::array<std::int32_t, 4>>& neighbors, const std::string& source) {
  // Why these checks suffice locally. With every tet positive, two tets
  // sharing a face lie on opposite sides of it exactly when the face has
  // opposite orientations in them (1, combinatorial: no rounding). Then
  // around an edge whose tets close up through their faces the dihedral
  // angles add up to a whole number of turns, and around a vertex whose tets
  // close up the solid angles to a whole number of spheres: one turn (one
  // sphere) is the only value an embedding allows, and 2, 3 separate it from
  // the next by a turn (a sphere), far beyond rounding. Where the tets do not
  // close up (the boundary, parts touching along an edge or at a point) the
  // angles of tets that do not overlap add up to less than a turn (a sphere);
  // more means that some direction is covered twice. Less does not mean the
  // opposite there: the last check (below) looks at the open facets around
  // each vertex. Each check is a pass over the tets or over each vertex's
  // star (sorted locally), so the whole is linear in the mesh for bounded
  // stars.
  const std::size_t nt = tets.size(), nv = positions.size();
  for (std::size_t t = 0; t < nt; ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    for (int k = 0; k < 4; ++k) {
      const std::int32_t code = neighbors[t][std::size_t(k)];
      if (code == kNoFace || std::size_t(code >> 2) < t) continue;
      const std::size_t u = std::size_t(code >> 2);
      const Tri f = tetFace(tets[t], k);
      if (sameOrientation(f, tetFace(tets[u], code & 3))) {
        // Named first: the tet with more open faces (a tet given a wrong
        // vertex no longer matches its old neighbours), else the later one.
        auto open = [&](std::size_t x) { return std::count(neighbors[x].begin(), neighbors[x].end(), kNoFace); };
        const std::size_t named = open(t) > open(u) ? t : u, other = named == t ? u : t;
        throw InputError(source, describeTet(named, tets[named]) + " overlaps " + describeTet(other, tets[other]) +
                                     ": both lie on the same side of their common face (" + std::to_string(f[0]) +
                                     ", " + std::to_string(f[1]) + ", " + std::to_string(f[2]) + ")");
      }
    }
  }
  throwIfCancelled();

  // The tets of each vertex (counting sort), for the stars below.
  std::vector<std::int64_t> first(nv + 1, 0);
  for (const Tet& q : tets)
    for (std::int32_t v : q) ++first[std::size_t(v) + 1];
  for (std::size_t v = 0; v < nv; ++v) first[v + 1] += first[v];
  throwIfCancelled();
  std::vector<std::int32_t> star(static_cast<std::size_t>(first[nv]));
  {
    std::vector<std::int64_t> fill(first.begin(), first.end() - 1);
    for (std::size_t t = 0; t < nt; ++t)
      for (std::int32_t v : tets[t]) star[std::size_t(fill[std::size_t(v)]++)] = std::int32_t(t);
  }
  throwIfCancelled();

  // Around each edge (v, w), found from its smaller end point v.
  struct Incidence {
    std::int32_t w, tet;
    double angle;
  };
  std::vector<Incidence> around;
  std::vector<std::int32_t> group;
  for (std::size_t v = 0; v < nv; ++v) {
    throwIfCancelled();  // seconds on a mesh of millions of tets
    around.clear();
    for (std::int64_t i = first[v]; i < first[v + 1]; ++i) {
      const std::int32_t t = star[std::size_t(i)];
      const Tet& q = tets[std::size_t(t)];
      int iv = 0;
      while (q[std::size_t(iv)] != std::int32_t(v)) ++iv;
      for (int j = 0; j < 4; ++j) {
        if (j == iv || q[std::size_t(j)] < std::int32_t(v)) continue;
        int k = 0;
        while (k == iv || k == j) ++k;
        int l = 0;
        while (l == iv || l == j || l == k) ++l;
        const double angle = dihedralAngle(positions[v], positions[std::size_t(q[std::size_t(j)])],
                                           positions[std::size_t(q[std::size_t(k)])], positions[std::size_t(q[std::size_t(l)])]);
        around.push_back({q[std::size_t(j)], t, angle});
      }
    }
    std::sort(around.begin(), around.end(),
              [](const Incidence& x, const Incidence& y) { return x.w < y.w || (x.w == y.w && x.tet < y.tet); });
    for (std::size_t i = 0; i < around.size();) {
      std::size_t j = i;
      double sum = 0.0;
      for (; j < around.size() && around[j].w == around[i].w; ++j) sum += around[j].angle;
      if (sum > kTurn + kAngleSlack) {
        group.clear();
        for (std::size_t n = i; n < j; ++n) group.push_back(around[n].tet);
        const std::int32_t t = smallestFan(tets, neighbors, group, {std::int32_t(v), around[i].w});
        char turns[32];
        std::snprintf(turns, sizeof turns, "%.2f", sum / kTurn);
        throw InputError(source, describeTet(std::size_t(t), tets[std::size_t(t)]) + " overlaps the tets around edge (" +
                                     std::to_string(v) + ", " + std::to_string(around[i].w) + "): their dihedral angles add up to " +
                                     turns + " turns");
      }
      i = j;
    }
  }

  // Around each vertex.
  std::vector<double> solid(nv, 0.0);
  for (std::size_t t = 0; t < nt; ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    const Tet& q = tets[t];
    for (int i = 0; i < 4; ++i)
      solid[std::size_t(q[std::size_t(i)])] +=
          solidAngle(positions[std::size_t(q[std::size_t(i)])], positions[std::size_t(q[std::size_t((i + 1) % 4)])],
                     positions[std::size_t(q[std::size_t((i + 2) % 4)])], positions[std::size_t(q[std::size_t((i + 3) % 4)])]);
  }
  throwIfCancelled();
  for (std::size_t v = 0; v < nv; ++v)
    if (solid[v] > 2 * kTurn + kAngleSlack) {
      group.assign(star.begin() + first[v], star.begin() + first[v + 1]);
      const std::int32_t t = smallestFan(tets, neighbors, group, {std::int32_t(v)});
      char spheres[32];
      std::snprintf(spheres, sizeof spheres, "%.2f", solid[v] / (2 * kTurn));
      throw InputError(source, describeTet(std::size_t(t), tets[std::size_t(t)]) + " overlaps the tets around vertex " +
                                   std::to_string(v) + ": their solid angles add up to " + spheres + " spheres");
    }

  // Around a vertex on an open facet the tets need not cover the sphere,
  // and the sums above cannot see a tet that covers part of its neighbours'
  // directions while leaving others open (a tet whose vertex was moved to a
  // neighbour's: the hole it leaves is as large as what it covers twice).
  // Seen from the vertex, the open facets through it are arcs bounding the
  // directions its tets cover (its link, a set of spherical triangles). If
  // the tets cover no direction twice, that boundary is made of simple
  // curves: no two arcs cross, and just beyond an arc (at its midpoint) no
  // other tet covers the direction. Each fan of tets is then an embedded
  // disc (or annulus), and two fans neither cross nor nest.
  throwIfCancelled();
  std::vector<std::int64_t> arcsFirst(nv + 1, 0);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 4; ++k)
      if (neighbors[t][std::size_t(k)] == kNoFace)
        for (int i = 0; i < 4; ++i)
          if (i != k) ++arcsFirst[std::size_t(tets[t][std::size_t(i)]) + 1];
  for (std::size_t v = 0; v < nv; ++v) arcsFirst[v + 1] += arcsFirst[v];
  throwIfCancelled();
  std::vector<std::int32_t> arcs(static_cast<std::size_t>(arcsFirst[nv]));  // 4 * tet + open face
  {
    std::vector<std::int64_t> fill(arcsFirst.begin(), arcsFirst.end() - 1);
    for (std::size_t t = 0; t < nt; ++t)
      for (int k = 0; k < 4; ++k)
        if (neighbors[t][std::size_t(k)] == kNoFace)
          for (int i = 0; i < 4; ++i)
            if (i != k) arcs[std::size_t(fill[std::size_t(tets[t][std::size_t(i)])]++)] = std::int32_t(4 * t + std::size_t(k));
  }
  struct Arc {
    std::int32_t x, y, tet;
    Eigen::Vector3d a, b;  // unit directions from the vertex to x and y
  };
  std::vector<Arc> boundary;
  auto overlapAt = [&](std::size_t v, std::int32_t t, std::int32_t u) {
    group.assign(star.begin() + first[v], star.begin() + first[v + 1]);
    const std::int32_t named = smallestFan(tets, neighbors, group, {std::int32_t(v)}) == u ? u : t;
    const std::int32_t other = named == t ? u : t;
    throw InputError(source, describeTet(std::size_t(named), tets[std::size_t(named)]) + " overlaps " +
                                 describeTet(std::size_t(other), tets[std::size_t(other)]) + " around vertex " + std::to_string(v));
  };
  for (std::size_t v = 0; v < nv; ++v) {
    if (v % 4096 == 0) throwIfCancelled();
    if (arcsFirst[v] == arcsFirst[v + 1]) continue;
    boundary.clear();
    const Eigen::Vector3d& pv = positions[v];
    for (std::int64_t i = arcsFirst[v]; i < arcsFirst[v + 1]; ++i) {
      const std::int32_t code = arcs[std::size_t(i)];
      const Tri f = tetFace(tets[std::size_t(code >> 2)], code & 3);
      int iv = 0;
      while (f[std::size_t(iv)] != std::int32_t(v)) ++iv;
      const std::int32_t x = f[std::size_t((iv + 1) % 3)], y = f[std::size_t((iv + 2) % 3)];
      boundary.push_back({x, y, code >> 2, (positions[std::size_t(x)] - pv).normalized(), (positions[std::size_t(y)] - pv).normalized()});
    }
    for (std::size_t i = 0; i < boundary.size(); ++i) {
      const Arc& p = boundary[i];
      for (std::size_t j = i + 1; j < boundary.size(); ++j) {
        const Arc& q = boundary[j];
        if (p.x == q.x || p.x == q.y || p.y == q.x || p.y == q.y) continue;
        if (arcsCross(p.a, p.b, q.a, q.b)) overlapAt(v, p.tet, q.tet);
      }
      const double reach = std::min((positions[std::size_t(p.x)] - pv).norm(), (positions[std::size_t(p.y)] - pv).norm());
      const Eigen::Vector3d middle = pv + 0.5 * reach * (p.a + p.b);
      for (std::int64_t n = first[v]; n < first[v + 1]; ++n) {
        const std::int32_t s = star[std::size_t(n)];
        if (s != p.tet && insideCone(positions, tets[std::size_t(s)], std::int32_t(v), middle, reach)) overlapAt(v, p.tet, s);
      }
    }
  }
}

}  // namespace vox::remesh
