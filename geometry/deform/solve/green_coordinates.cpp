#include "geometry/deform/solve/green_coordinates.h"

#include "geometry/error.h"
#include "geometry/parallel.h"
#include "geometry/progress.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <atomic>
#if defined(__x86_64__)
#include <immintrin.h>
#endif
#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <utility>

namespace vox {

namespace {

constexpr double kInvFourPi = 0.25 / std::numbers::pi;

// Calls body(begin, end) for consecutive ranges of `block` items covering
// [0, count), spread over every hardware thread.
template <class Body>
void forBlocks(std::size_t count, std::size_t block, Body&& body) {
  const auto blocks = std::int64_t((count + block - 1) / block);
  parallelFor(blocks, 0, [&](std::int64_t b) {
    const std::size_t begin = std::size_t(b) * block;
    body(begin, std::min(count, begin + block));
  });
}

struct CageEdge {
  std::int32_t a = 0, b = 0;
  Eigen::Vector3d s;  // unit direction a -> b
  double length = 0;
};

struct CageFace {
  std::array<std::int32_t, 3> v{};
  std::array<std::int32_t, 3> edge{};  // undirected edge of side i (v[i] -> v[i+1])
  Eigen::Vector3d n;                   // outward unit normal
  double doubleArea = 0;               // 2 |t|
  std::array<Eigen::Vector3d, 3> m;    // outward in-plane normal of side i
  std::array<double, 3> length{};      // length of side i
  Eigen::Matrix3d mm;                  // mm(i, k) = m_i . m_k
  bool degenerate = false;
};

struct CageGeometry {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<CageEdge> edges;
  std::vector<CageFace> faces;
};

// Edge table, per-face frames; rejects cages that are not closed 2-manifolds
// edge-wise (every edge must have exactly two faces), since Green's identity
// needs a closed boundary.
CageGeometry prepareCage(const TriMesh& cage) {
  cage.validate("cage");
  if (cage.faceCount() == 0) throw InputError("cage", "has no faces");
  CageGeometry g;
  g.vertices = cage.positions;
  std::map<std::pair<std::int32_t, std::int32_t>, std::pair<std::int32_t, int>> edgeIndex;  // -> (edge, face count)
  g.faces.resize(cage.faceCount());
  for (std::size_t j = 0; j < cage.faceCount(); ++j) {
    CageFace& f = g.faces[j];
    const Tri& t = cage.triangles[j];
    for (int i = 0; i < 3; ++i) f.v[std::size_t(i)] = t[std::size_t(i)];
    for (int i = 0; i < 3; ++i) {
      const std::int32_t a = t[std::size_t(i)], b = t[std::size_t((i + 1) % 3)];
      const auto key = std::minmax(a, b);
      auto [it, inserted] = edgeIndex.try_emplace({key.first, key.second}, std::int32_t(g.edges.size()), 0);
      if (inserted) {
        CageEdge e;
        e.a = key.first;
        e.b = key.second;
        const Eigen::Vector3d d = g.vertices[std::size_t(e.b)] - g.vertices[std::size_t(e.a)];
        e.length = d.norm();
        e.s = e.length > 0 ? Eigen::Vector3d(d / e.length) : Eigen::Vector3d::Zero();
        g.edges.push_back(e);
      }
      ++it->second.second;
      f.edge[std::size_t(i)] = it->second.first;
    }
    const Eigen::Vector3d& a = g.vertices[std::size_t(f.v[0])];
    const Eigen::Vector3d cross = (g.vertices[std::size_t(f.v[1])] - a).cross(g.vertices[std::size_t(f.v[2])] - a);
    f.doubleArea = cross.norm();
    // A zero-area face bounds nothing: its integrals vanish.
    f.degenerate = !(f.doubleArea > 0.0);
    if (f.degenerate) continue;
    f.n = cross / f.doubleArea;
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d d = g.vertices[std::size_t(f.v[std::size_t((i + 1) % 3)])] - g.vertices[std::size_t(f.v[std::size_t(i)])];
      f.length[std::size_t(i)] = d.norm();
      f.m[std::size_t(i)] = (d / f.length[std::size_t(i)]).cross(f.n);
    }
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) f.mm(i, k) = f.m[std::size_t(i)].dot(f.m[std::size_t(k)]);
  }
  for (const auto& [key, value] : edgeIndex)
    if (value.second != 2)
      throw InputError("cage", "is not closed: edge (" + std::to_string(key.first) + ", " + std::to_string(key.second) +
                                   ") belongs to " + std::to_string(value.second) + " face(s)");
  return g;
}

// int_e ds / |xi - eta| over the segment a -> b, with da = a - eta, db = b - eta.
// ln((Rb + lb) / (Ra + la)) = ln((Ra - la) / (Rb - lb)); the form whose
// logarithm argument has no cancellation is chosen, the difference of the two
// terms comes from its factored form len (1 +- (la + lb) / (Ra + Rb)), and the
// term on the far side of the foot of eta uses R + l = d^2 / (R - l).
double lineIntegral(const Eigen::Vector3d& da, const Eigen::Vector3d& db, double ra, double rb, const CageEdge& e) {
  if (!(e.length > 0)) return 0.0;
  const double la = da.dot(e.s);
  const double lb = db.dot(e.s);
  const double d2 = da.cross(e.s).squaredNorm();
  const double sum = la + lb;
  const double rsum = ra + rb;
  if (sum >= 0.0) {
    const double near = la >= 0.0 ? ra + la : d2 / (ra - la);
    const double diff = e.length * (1.0 + sum / rsum);
    // eta on the segment itself: the integral diverges, but every term that
    // uses it is multiplied by a distance that vanishes there.
    return near > 0.0 ? std::log1p(diff / near) : 0.0;
  }
  const double near = lb <= 0.0 ? rb - lb : d2 / (rb + lb);
  const double diff = e.length * (1.0 - sum / rsum);
  return near > 0.0 ? std::log1p(diff / near) : 0.0;
}

// Signed solid angle of face f seen from eta (van Oosterom-Strackee), positive
// when eta is on the inner side. The triple product d0.(d1 x d2) equals
// -2|t| h for a planar triangle, h the signed height of eta (see faceHeight).
// Near a side of the face both det and denom are small differences of terms
// of size R^3 and their ratio (the angle around that side) would lose
// log10(R / distance) digits: there they are recomputed in long double from
// the exact differences a - eta.
double solidAngle(const CageFace& f, const std::vector<Eigen::Vector3d>& vertices, const Eigen::Vector3d& eta, double h,
                  const Eigen::Vector3d& d0, const Eigen::Vector3d& d1, const Eigen::Vector3d& d2, double r0, double r1,
                  double r2) {
  const double det = -f.doubleArea * h;
  const double denom = r0 * r1 * r2 + d0.dot(d1) * r2 + d0.dot(d2) * r1 + d1.dot(d2) * r0;
  const double scale = r0 * r1 * r2;
  if (std::abs(det) + std::abs(denom) > 1e-3 * scale) return 2.0 * std::atan2(det, denom);
  using Vec = Eigen::Matrix<long double, 3, 1>;
  const Vec e = eta.cast<long double>();
  const Vec a = vertices[std::size_t(f.v[0])].cast<long double>() - e;
  const Vec b = vertices[std::size_t(f.v[1])].cast<long double>() - e;
  const Vec c = vertices[std::size_t(f.v[2])].cast<long double>() - e;
  const long double ra = a.norm(), rb = b.norm(), rc = c.norm();
  const long double detL = a.dot(b.cross(c));
  const long double denomL = ra * rb * rc + a.dot(b) * rc + a.dot(c) * rb + b.dot(c) * ra;
  return double(2.0L * std::atan2(detL, denomL));
}

// Signed height of eta above the plane of f (negative on the inner side),
// taken from the face vertex nearest to eta: the rounding error of d.n is
// eps |d|, which makes h accurate to eps * (distance to the nearest vertex)
// rather than eps * (face size) when eta is close to a vertex.
double faceHeight(const CageFace& f, const Eigen::Vector3d& d0, const Eigen::Vector3d& d1, const Eigen::Vector3d& d2,
                  double r0, double r1, double r2) {
  const Eigen::Vector3d& nearest = r0 <= r1 ? (r0 <= r2 ? d0 : d2) : (r1 <= r2 ? d1 : d2);
  return -nearest.dot(f.n);
}

struct PointWorkspace {
  std::vector<Eigen::Vector3d> d;  // cage vertex - eta
  std::vector<double> r;           // |d|
  std::vector<double> line;        // per cage edge
  explicit PointWorkspace(const CageGeometry& g) : d(g.vertices.size()), r(g.vertices.size()), line(g.edges.size()) {}
};

// Writes phi (#V) then psi (#F) of eta into out.
void coordinatesOfPoint(const CageGeometry& g, const Eigen::Vector3d& eta, PointWorkspace& w, double* out) {
  const std::size_t nv = g.vertices.size();
  for (std::size_t i = 0; i < nv; ++i) {
    w.d[i] = g.vertices[i] - eta;
    w.r[i] = w.d[i].norm();
  }
  for (std::size_t e = 0; e < g.edges.size(); ++e) {
    const CageEdge& edge = g.edges[e];
    const auto a = std::size_t(edge.a), b = std::size_t(edge.b);
    w.line[e] = lineIntegral(w.d[a], w.d[b], w.r[a], w.r[b], edge);
  }
  double* phi = out;
  double* psi = out + nv;
  std::fill(phi, phi + nv, 0.0);
  for (std::size_t j = 0; j < g.faces.size(); ++j) {
    const CageFace& f = g.faces[j];
    if (f.degenerate) {
      psi[j] = 0.0;
      continue;
    }
    const auto i0 = std::size_t(f.v[0]), i1 = std::size_t(f.v[1]), i2 = std::size_t(f.v[2]);
    const Eigen::Vector3d& d0 = w.d[i0];
    const Eigen::Vector3d& d1 = w.d[i1];
    const Eigen::Vector3d& d2 = w.d[i2];
    const double h = faceHeight(f, d0, d1, d2, w.r[i0], w.r[i1], w.r[i2]);
    const double omega = solidAngle(f, g.vertices, eta, h, d0, d1, d2, w.r[i0], w.r[i1], w.r[i2]);
    // t_i: signed in-plane distance from the projection of eta to side i
    // (positive when the projection is on the inner side of that side).
    const Eigen::Vector3d t(d0.dot(f.m[0]), d1.dot(f.m[1]), d2.dot(f.m[2]));
    const Eigen::Vector3d line(w.line[std::size_t(f.edge[0])], w.line[std::size_t(f.edge[1])], w.line[std::size_t(f.edge[2])]);
    // int_t 1/R dA = sum_i t_i L_i + h omega (divergence theorem in the plane).
    psi[j] = kInvFourPi * (t.dot(line) + h * omega);
    // Linear density Gamma_l = Gamma_l(p) + g_l.(xi - p) with Gamma_l(p) =
    // t_o len_o / 2|t| and g_l = -m_o len_o / 2|t|, o the side opposite l;
    // int_t (xi - p)/R^3 dA = -sum_i m_i L_i.
    const Eigen::Vector3d mLine = f.mm * line;
    for (int l = 0; l < 3; ++l) {
      const int o = (l + 1) % 3;
      const double scale = kInvFourPi * f.length[std::size_t(o)] / f.doubleArea;
      phi[std::size_t(f.v[std::size_t(l)])] += scale * (t[o] * omega - h * mLine[o]);
    }
  }
}

// The per-frame product: out[p] = base[p] + coefficients(p, :) * basis + offset.
// It is bound by memory traffic when it runs at AVX2 + FMA speed; the
// portable kernel (SSE2 through Eigen's fixed-size arrays) is compute bound
// at about twice the time. The AVX2 kernels are compiled for that target only
// and chosen at run time. Accumulation is in float for float and half
// coefficients, in double for double ones.
template <typename Coefficient, typename Accumulator>
void applyRows(const Coefficient* coefficients, Eigen::Index stride, const Accumulator* basis, std::size_t begin, std::size_t end,
               const Eigen::Vector3d& offset, std::span<Eigen::Vector3d> out, std::span<const Eigen::Vector3d> base) {
  constexpr Eigen::Index kBlock = GreenCoordinates::kGreenColumnBlock;
  using Block = Eigen::Array<Accumulator, kBlock, 1>;
  const Accumulator* bx = basis;
  const Accumulator* by = basis + stride;
  const Accumulator* bz = basis + 2 * stride;
  for (std::size_t p = begin; p < end; ++p) {
    const Coefficient* row = coefficients + Eigen::Index(p) * stride;
    Block x = Block::Zero(), y = Block::Zero(), z = Block::Zero();
    for (Eigen::Index c = 0; c < stride; c += kBlock) {
      const Block a = Eigen::Map<const Eigen::Array<Coefficient, kBlock, 1>>(row + c).template cast<Accumulator>();
      x += a * Eigen::Map<const Block>(bx + c);
      y += a * Eigen::Map<const Block>(by + c);
      z += a * Eigen::Map<const Block>(bz + c);
    }
    const Eigen::Vector3d sum(double(x.sum()), double(y.sum()), double(z.sum()));
    out[p] = base.empty() ? Eigen::Vector3d(sum + offset) : Eigen::Vector3d(base[p] + (sum + offset));
  }
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define VOX_GREEN_AVX2 1

__attribute__((target("avx2,fma,f16c"))) double horizontalSum(__m256 v) {
  const __m128 h = _mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  const __m128 q = _mm_add_ps(h, _mm_movehl_ps(h, h));
  return double(_mm_cvtss_f32(_mm_add_ss(q, _mm_shuffle_ps(q, q, 1))));
}

// 8 coefficients as floats: loaded, or converted from binary16.
__attribute__((target("avx2,fma,f16c"))) inline __m256 load8(const float* p) { return _mm256_loadu_ps(p); }
__attribute__((target("avx2,fma,f16c"))) inline __m256 load8(const Eigen::half* p) {
  return _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
}

template <typename Coefficient>
__attribute__((target("avx2,fma,f16c"))) void applyRowsAvx2(const Coefficient* coefficients, Eigen::Index stride,
                                                            const float* basis, std::size_t begin, std::size_t end,
                                                            const Eigen::Vector3d& offset, std::span<Eigen::Vector3d> out,
                                                            std::span<const Eigen::Vector3d> base) {
  const float* bx = basis;
  const float* by = basis + stride;
  const float* bz = basis + 2 * stride;
  for (std::size_t p = begin; p < end; ++p) {
    const Coefficient* row = coefficients + Eigen::Index(p) * stride;
    // Two independent accumulator sets hide the FMA latency.
    __m256 x0 = _mm256_setzero_ps(), y0 = x0, z0 = x0, x1 = x0, y1 = x0, z1 = x0;
    for (Eigen::Index c = 0; c < stride; c += 16) {
      const __m256 a0 = load8(row + c);
      const __m256 a1 = load8(row + c + 8);
      x0 = _mm256_fmadd_ps(a0, _mm256_loadu_ps(bx + c), x0);
      y0 = _mm256_fmadd_ps(a0, _mm256_loadu_ps(by + c), y0);
      z0 = _mm256_fmadd_ps(a0, _mm256_loadu_ps(bz + c), z0);
      x1 = _mm256_fmadd_ps(a1, _mm256_loadu_ps(bx + c + 8), x1);
      y1 = _mm256_fmadd_ps(a1, _mm256_loadu_ps(by + c + 8), y1);
      z1 = _mm256_fmadd_ps(a1, _mm256_loadu_ps(bz + c + 8), z1);
    }
    const Eigen::Vector3d sum(horizontalSum(_mm256_add_ps(x0, x1)), horizontalSum(_mm256_add_ps(y0, y1)),
                              horizontalSum(_mm256_add_ps(z0, z1)));
    out[p] = base.empty() ? Eigen::Vector3d(sum + offset) : Eigen::Vector3d(base[p] + (sum + offset));
  }
}

bool haveAvx2() {
  static const bool have = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("f16c");
  return have;
}
#endif

// Single-precision coefficients (float or half) against a float basis.
template <typename Coefficient>
void applyRowsSingle(const Coefficient* coefficients, Eigen::Index stride, const float* basis, std::size_t begin, std::size_t end,
                     const Eigen::Vector3d& offset, std::span<Eigen::Vector3d> out, std::span<const Eigen::Vector3d> base) {
#if VOX_GREEN_AVX2
  if (haveAvx2()) {
    applyRowsAvx2(coefficients, stride, basis, begin, end, offset, out, base);
    return;
  }
#endif
  applyRows(coefficients, stride, basis, begin, end, offset, out, base);
}

}  // namespace

GreenCoordinates greenCoordinates(const TriMesh& cage, std::span<const Eigen::Vector3d> points, GreenPrecision precision) {
  const CageGeometry g = prepareCage(cage);
  GreenCoordinates gc;
  gc.rows_ = Eigen::Index(points.size());
  gc.cageVertices_ = std::int32_t(g.vertices.size());
  gc.cageFaces_ = std::int32_t(g.faces.size());
  const Eigen::Index used = Eigen::Index(g.vertices.size() + g.faces.size());
  constexpr Eigen::Index kBlock = GreenCoordinates::kGreenColumnBlock;
  gc.stride_ = (used + kBlock - 1) / kBlock * kBlock;
  gc.precision_ = precision;
  switch (precision) {
    case GreenPrecision::Double: gc.d_.setZero(gc.rows_, gc.stride_); break;
    case GreenPrecision::Float: gc.f_.setZero(gc.rows_, gc.stride_); break;
    case GreenPrecision::Half: gc.h_.setConstant(gc.rows_, gc.stride_, Eigen::half(0.0f)); break;
  }

  for (const Eigen::Vector3d& p : points)
    if (!p.allFinite()) throw InputError("points", "a point to embed in the cage has a non-finite coordinate");

  std::atomic<std::size_t> done{0};
  std::atomic<int> reported{-1};
  reportProgress("green coordinates", 0.0);
  forBlocks(points.size(), 256, [&](std::size_t begin, std::size_t end) {
    PointWorkspace w(g);
    std::vector<double> row(static_cast<std::size_t>(used));
    for (std::size_t p = begin; p < end; ++p) {
      if (precision == GreenPrecision::Double) {
        coordinatesOfPoint(g, points[p], w, gc.d_.row(Eigen::Index(p)).data());
      } else if (precision == GreenPrecision::Float) {
        coordinatesOfPoint(g, points[p], w, row.data());
        float* dst = gc.f_.row(Eigen::Index(p)).data();
        for (Eigen::Index c = 0; c < used; ++c) dst[c] = float(row[std::size_t(c)]);
      } else {
        coordinatesOfPoint(g, points[p], w, row.data());
        Eigen::half* dst = gc.h_.row(Eigen::Index(p)).data();
        for (Eigen::Index c = 0; c < used; ++c) dst[c] = Eigen::half(float(row[std::size_t(c)]));
      }
    }
    const std::size_t total = done += end - begin;
    const int percent = int(100.0 * double(total) / double(points.size()));
    int last = reported.load();
    if (percent > last && percent < 100 && reported.compare_exchange_strong(last, percent))
      reportProgress("green coordinates", double(total) / double(points.size()));
  });
  reportProgress("green coordinates", 1.0);
  return gc;
}

Eigen::VectorXd greenStretchFactors(const TriMesh& restCage, std::span<const Eigen::Vector3d> deformed) {
  if (deformed.size() != restCage.vertexCount())
    throw InputError("cage", "deformed cage has " + std::to_string(deformed.size()) + " vertices, rest cage " +
                                 std::to_string(restCage.vertexCount()));
  Eigen::VectorXd s(Eigen::Index(restCage.faceCount()));
  for (std::size_t j = 0; j < restCage.faceCount(); ++j) {
    const Tri& t = restCage.triangles[j];
    const auto a = std::size_t(t[0]), b = std::size_t(t[1]), c = std::size_t(t[2]);
    const Eigen::Vector3d u = restCage.positions[b] - restCage.positions[a];
    const Eigen::Vector3d v = restCage.positions[c] - restCage.positions[a];
    const Eigen::Vector3d u2 = deformed[b] - deformed[a];
    const Eigen::Vector3d v2 = deformed[c] - deformed[a];
    const double area = 0.5 * u.cross(v).norm();
    const double num = u2.squaredNorm() * v.squaredNorm() - 2.0 * u2.dot(v2) * u.dot(v) + v2.squaredNorm() * u.squaredNorm();
    s[Eigen::Index(j)] = area > 0 ? std::sqrt(std::max(0.0, num)) / (std::sqrt(8.0) * area) : 1.0;
  }
  return s;
}

GreenCageFrame greenCageFrame(const TriMesh& restCage, std::span<const Eigen::Vector3d> deformed, Eigen::Index stride) {
  const Eigen::VectorXd s = greenStretchFactors(restCage, deformed);
  const auto nv = Eigen::Index(restCage.vertexCount());
  const auto nf = Eigen::Index(restCage.faceCount());
  if (stride < nv + nf) throw RuntimeFailure("green cage frame: stride smaller than the cage's vertex and face count");
  GreenCageFrame frame;
  frame.rows.setZero(stride, 3);
  for (const Eigen::Vector3d& p : deformed) frame.offset += p;
  if (nv > 0) frame.offset /= double(nv);
  for (Eigen::Index i = 0; i < nv; ++i) frame.rows.row(i) = (deformed[std::size_t(i)] - frame.offset).transpose();
  for (Eigen::Index j = 0; j < nf; ++j) {
    const Tri& t = restCage.triangles[std::size_t(j)];
    const Eigen::Vector3d& a = deformed[std::size_t(t[0])];
    const Eigen::Vector3d cross = (deformed[std::size_t(t[1])] - a).cross(deformed[std::size_t(t[2])] - a);
    const double norm = cross.norm();
    if (norm > 0) frame.rows.row(nv + j) = (s[j] / norm * cross).transpose();
  }
  return frame;
}

GreenCageFrame greenCageDisplacement(const TriMesh& restCage, std::span<const Eigen::Vector3d> deformed, Eigen::Index stride) {
  GreenCageFrame frame = greenCageFrame(restCage, deformed, stride);
  const GreenCageFrame rest = greenCageFrame(restCage, restCage.positions, stride);
  frame.rows -= rest.rows;
  frame.offset -= rest.offset;
  return frame;
}

void applyGreenCoordinateRows(const GreenCoordinates& coordinates, const GreenCageFrame& frame, std::size_t begin,
                              std::size_t end, std::span<Eigen::Vector3d> out, std::span<const Eigen::Vector3d> base) {
  if (out.size() != std::size_t(coordinates.pointCount()) || (!base.empty() && base.size() != out.size()) ||
      end > out.size() || begin > end)
    throw RuntimeFailure("green coordinates: output size or row range does not match the point count");
  if (frame.rows.rows() != coordinates.stride()) throw RuntimeFailure("green coordinates: cage frame of the wrong size");
  if (coordinates.precision() == GreenPrecision::Double) {
    const Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::RowMajor> basis = frame.rows.transpose();
    applyRows(coordinates.coefficientsDouble().data(), coordinates.stride(), basis.data(), begin, end, frame.offset, out, base);
    return;
  }
  const Eigen::Matrix<float, 3, Eigen::Dynamic, Eigen::RowMajor> basis = frame.rows.transpose().cast<float>();
  if (coordinates.precision() == GreenPrecision::Float)
    applyRowsSingle(coordinates.coefficientsFloat().data(), coordinates.stride(), basis.data(), begin, end, frame.offset, out, base);
  else
    applyRowsSingle(coordinates.coefficientsHalf().data(), coordinates.stride(), basis.data(), begin, end, frame.offset, out, base);
}

void applyGreenCoordinates(const GreenCoordinates& coordinates, const GreenCageFrame& frame, std::span<Eigen::Vector3d> out,
                           std::span<const Eigen::Vector3d> base) {
  // One contiguous range of rows per thread.
  const std::size_t n = out.size();
  const auto threads = std::size_t(workerThreads(0));
  const std::size_t chunk = std::max<std::size_t>(1, (n + threads - 1) / threads);
  if (n == 0) applyGreenCoordinateRows(coordinates, frame, 0, 0, out, base);  // argument checks only
  forBlocks(n, chunk, [&](std::size_t begin, std::size_t end) { applyGreenCoordinateRows(coordinates, frame, begin, end, out, base); });
}

std::vector<Eigen::Vector3d> greenDeform(const GreenCoordinates& coordinates, const TriMesh& restCage,
                                         std::span<const Eigen::Vector3d> deformed) {
  std::vector<Eigen::Vector3d> out(std::size_t(coordinates.pointCount()));
  applyGreenCoordinates(coordinates, greenCageFrame(restCage, deformed, coordinates.stride()), out);
  return out;
}

double cageWindingNumber(const TriMesh& cage, const Eigen::Vector3d& p) {
  double total = 0.0;
  for (const Tri& t : cage.triangles) {
    const Eigen::Vector3d d0 = cage.positions[std::size_t(t[0])] - p;
    const Eigen::Vector3d d1 = cage.positions[std::size_t(t[1])] - p;
    const Eigen::Vector3d d2 = cage.positions[std::size_t(t[2])] - p;
    const double r0 = d0.norm(), r1 = d1.norm(), r2 = d2.norm();
    const double det = d0.dot(d1.cross(d2));
    const double denom = r0 * r1 * r2 + d0.dot(d1) * r2 + d0.dot(d2) * r1 + d1.dot(d2) * r0;
    total += 2.0 * std::atan2(det, denom);
  }
  return total * kInvFourPi;
}

std::vector<std::uint8_t> insideCage(const TriMesh& cage, std::span<const Eigen::Vector3d> points) {
  cage.validate("cage");
  std::vector<std::uint8_t> inside(points.size(), 0);
  forBlocks(points.size(), 512, [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p) inside[p] = cageWindingNumber(cage, points[p]) > 0.5 ? 1 : 0;
  });
  return inside;
}

}  // namespace vox
