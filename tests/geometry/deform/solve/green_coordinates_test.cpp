#include "tests/geometry/deform/cage_fixtures.h"
#include "geometry/deform/solve/green_coordinates.h"
#include "geometry/error.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>

namespace vox {
namespace {

using test::bumpyCage;
using test::randomInteriorPoints;

std::string sci(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

double cageSize(const TriMesh& cage) {
  Eigen::Vector3d lo = cage.positions[0], hi = cage.positions[0];
  for (const auto& p : cage.positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).norm();
}

Eigen::Vector3d faceNormal(const TriMesh& cage, std::size_t j) {
  const Tri& t = cage.triangles[j];
  const auto& a = cage.positions[std::size_t(t[0])];
  return (cage.positions[std::size_t(t[1])] - a).cross(cage.positions[std::size_t(t[2])] - a).normalized();
}

// sum_i phi_i v_i + sum_j psi_j n_j for point p.
Eigen::Vector3d reproduce(const GreenCoordinates& gc, const TriMesh& cage, Eigen::Index p) {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < cage.vertexCount(); ++i) x += gc.phi(p, std::int32_t(i)) * cage.positions[i];
  for (std::size_t j = 0; j < cage.faceCount(); ++j) x += gc.psi(p, std::int32_t(j)) * faceNormal(cage, j);
  return x;
}

// Points at distance delta inside the cage from face centroids, edge
// midpoints and vertices (a few of each).
std::vector<Eigen::Vector3d> pointsNearCage(const TriMesh& cage, double delta) {
  std::vector<Eigen::Vector3d> vertexNormal(cage.vertexCount(), Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> out;
  for (std::size_t j = 0; j < cage.faceCount(); ++j) {
    const Tri& t = cage.triangles[j];
    const Eigen::Vector3d n = faceNormal(cage, j);
    for (int k = 0; k < 3; ++k) vertexNormal[std::size_t(t[std::size_t(k)])] += n;
    if (j % 7 == 0) {
      const Eigen::Vector3d c = (cage.positions[std::size_t(t[0])] + cage.positions[std::size_t(t[1])] + cage.positions[std::size_t(t[2])]) / 3.0;
      out.push_back(c - delta * n);
      // Projection on a side (its midpoint) and near it (1e-3 of the way to the centroid).
      const Eigen::Vector3d m = 0.5 * (cage.positions[std::size_t(t[0])] + cage.positions[std::size_t(t[1])]);
      out.push_back(m - delta * n);
      out.push_back(m + 1e-3 * (c - m) - delta * n);
    }
  }
  for (std::size_t i = 0; i < cage.vertexCount(); i += 11) out.push_back(cage.positions[i] - delta * vertexNormal[i].normalized());
  return out;
}

// Adaptive reference quadrature of the Green integrals over one face:
// psi = 1/4pi int 1/R, phi_l = 1/4pi int Gamma_l n.(xi - eta)/R^3, by
// subdividing until each piece is small compared to its distance to eta, then
// a collapsed-square Gauss-Legendre rule of order 12 on each piece.
struct FaceIntegrals {
  double psi = 0;
  std::array<double, 3> phi{};
};

void gaussLegendre(int n, std::vector<double>& x, std::vector<double>& w) {
  x.resize(std::size_t(n));
  w.resize(std::size_t(n));
  for (int i = 0; i < n; ++i) {
    double z = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
    double dp = 0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1, p1 = 0;
      for (int k = 1; k <= n; ++k) {
        const double p2 = p1;
        p1 = p0;
        p0 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p2) / k;
      }
      dp = n * (z * p0 - p1) / (z * z - 1.0);
      const double dz = p0 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    x[std::size_t(i)] = 0.5 * (1.0 - z);
    w[std::size_t(i)] = 1.0 / ((1.0 - z * z) * dp * dp);
  }
}

void integrateFace(const std::array<Eigen::Vector3d, 3>& face, const Eigen::Vector3d& n, const std::array<Eigen::Vector3d, 3>& bary,
                   const Eigen::Vector3d& eta, int depth, FaceIntegrals& acc) {
  auto point = [&](const Eigen::Vector3d& l) { return l[0] * face[0] + l[1] * face[1] + l[2] * face[2]; };
  const Eigen::Vector3d a = point(bary[0]), b = point(bary[1]), c = point(bary[2]);
  const double diam = std::max({(a - b).norm(), (b - c).norm(), (c - a).norm()});
  const double dist = (eta - (a + b + c) / 3.0).norm();
  if (depth < 14 && diam > 0.5 * dist) {
    const Eigen::Vector3d ab = 0.5 * (bary[0] + bary[1]), bc = 0.5 * (bary[1] + bary[2]), ca = 0.5 * (bary[2] + bary[0]);
    integrateFace(face, n, {bary[0], ab, ca}, eta, depth + 1, acc);
    integrateFace(face, n, {ab, bary[1], bc}, eta, depth + 1, acc);
    integrateFace(face, n, {ca, bc, bary[2]}, eta, depth + 1, acc);
    integrateFace(face, n, {ab, bc, ca}, eta, depth + 1, acc);
    return;
  }
  static std::vector<double> x, w;
  if (x.empty()) gaussLegendre(12, x, w);
  const double area2 = (b - a).cross(c - a).norm();
  for (std::size_t i = 0; i < x.size(); ++i)
    for (std::size_t j = 0; j < x.size(); ++j) {
      const double u = x[i], v = x[j];
      // xi(u, v) = A + u (B - A) + u v (C - B); dA = u |(B-A) x (C-B)| du dv.
      const Eigen::Vector3d l = bary[0] + u * (bary[1] - bary[0]) + u * v * (bary[2] - bary[1]);
      const Eigen::Vector3d xi = point(l);
      const double weight = w[i] * w[j] * u * area2;
      const Eigen::Vector3d d = xi - eta;
      const double r = d.norm();
      acc.psi += weight / r;
      const double kernel = n.dot(d) / (r * r * r);
      for (int k = 0; k < 3; ++k) acc.phi[std::size_t(k)] += weight * l[k] * kernel;
    }
}

TEST(GreenCoordinates, MatchNumericalIntegration) {
  const TriMesh cage = bumpyCage(1, 1.0, 0.25, {0.3, -0.2, 0.1});
  std::mt19937 rng(7);
  const auto points = randomInteriorPoints(cage, 12, 0.05, rng);
  const GreenCoordinates gc = greenCoordinates(cage, points);
  double worst = 0;
  for (std::size_t p = 0; p < points.size(); ++p) {
    std::vector<double> phi(cage.vertexCount(), 0.0);
    for (std::size_t j = 0; j < cage.faceCount(); ++j) {
      const Tri& t = cage.triangles[j];
      const std::array<Eigen::Vector3d, 3> face{cage.positions[std::size_t(t[0])], cage.positions[std::size_t(t[1])],
                                                cage.positions[std::size_t(t[2])]};
      FaceIntegrals acc;
      integrateFace(face, faceNormal(cage, j), {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()},
                    points[p], 0, acc);
      const double psi = acc.psi / (4.0 * std::numbers::pi);
      worst = std::max(worst, std::abs(psi - gc.psi(Eigen::Index(p), std::int32_t(j))));
      for (int k = 0; k < 3; ++k) phi[std::size_t(t[std::size_t(k)])] += acc.phi[std::size_t(k)] / (4.0 * std::numbers::pi);
    }
    for (std::size_t i = 0; i < cage.vertexCount(); ++i)
      worst = std::max(worst, std::abs(phi[i] - gc.phi(Eigen::Index(p), std::int32_t(i))));
  }
  RecordProperty("max_abs_difference", sci(worst));
  EXPECT_LT(worst, 1e-10);
}

TEST(GreenCoordinates, IdentityCageReproducesPoints) {
  const TriMesh cage = bumpyCage(2, 150.0, 0.3, {400.0, -250.0, 900.0});  // mm, far from the origin
  const double size = cageSize(cage);
  std::mt19937 rng(11);
  std::vector<Eigen::Vector3d> points = randomInteriorPoints(cage, 200, 0.02 * size, rng);
  const std::size_t deep = points.size();
  for (double delta : {1e-3, 1e-6, 1e-9}) {
    const auto near = pointsNearCage(cage, delta * size);
    points.insert(points.end(), near.begin(), near.end());
  }
  const GreenCoordinates gc = greenCoordinates(cage, points);
  double worstDeep = 0, worstNear = 0, worstSum = 0;
  for (std::size_t p = 0; p < points.size(); ++p) {
    const double err = (reproduce(gc, cage, Eigen::Index(p)) - points[p]).norm() / size;
    (p < deep ? worstDeep : worstNear) = std::max(p < deep ? worstDeep : worstNear, err);
    double sum = 0;
    for (std::size_t i = 0; i < cage.vertexCount(); ++i) sum += gc.phi(Eigen::Index(p), std::int32_t(i));
    worstSum = std::max(worstSum, std::abs(sum - 1.0));
    for (std::size_t j = 0; j < cage.faceCount(); ++j) ASSERT_GE(gc.psi(Eigen::Index(p), std::int32_t(j)), 0.0);
  }
  RecordProperty("deep_relative_error", sci(worstDeep));
  RecordProperty("near_relative_error", sci(worstNear));
  RecordProperty("partition_of_unity_error", sci(worstSum));
  EXPECT_LT(worstDeep, 1e-9);
  EXPECT_LT(worstNear, 1e-9);
  EXPECT_LT(worstSum, 1e-9);

  // The per-frame path (greenDeform with the rest cage, stretch 1) agrees.
  const auto again = greenDeform(gc, cage, cage.positions);
  double worstApply = 0;
  for (std::size_t p = 0; p < points.size(); ++p) worstApply = std::max(worstApply, (again[p] - points[p]).norm() / size);
  EXPECT_LT(worstApply, 1e-9);
}

TEST(GreenCoordinates, SimilarityOfTheCageMovesInteriorPointsAlike) {
  const TriMesh cage = bumpyCage(2, 150.0, 0.3, {400.0, -250.0, 900.0});
  const double size = cageSize(cage);
  std::mt19937 rng(5);
  std::vector<Eigen::Vector3d> points = randomInteriorPoints(cage, 150, 0.01 * size, rng);
  const auto near = pointsNearCage(cage, 1e-7 * size);
  points.insert(points.end(), near.begin(), near.end());
  for (GreenPrecision precision : {GreenPrecision::Double, GreenPrecision::Float}) {
    const GreenCoordinates gc = greenCoordinates(cage, points, precision);
    for (double scale : {1.0, 1.7}) {
      const Eigen::Matrix3d r = Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
      const Eigen::Vector3d shift(-120.0, 333.0, 57.0);
      auto map = [&](const Eigen::Vector3d& x) -> Eigen::Vector3d { return scale * (r * x) + shift; };
      std::vector<Eigen::Vector3d> moved;
      for (const auto& v : cage.positions) moved.push_back(map(v));
      const Eigen::VectorXd s = greenStretchFactors(cage, moved);
      EXPECT_NEAR(s.minCoeff(), scale, 1e-12);
      EXPECT_NEAR(s.maxCoeff(), scale, 1e-12);
      const auto out = greenDeform(gc, cage, moved);
      double worst = 0;
      for (std::size_t p = 0; p < points.size(); ++p) worst = std::max(worst, (out[p] - map(points[p])).norm() / (scale * size));
      const double tolerance = precision == GreenPrecision::Double ? 1e-9 : 2e-6;
      RecordProperty(std::string(precision == GreenPrecision::Double ? "double" : "float") + "_scale_" +
                         std::to_string(scale) + "_relative_error",
                     sci(worst));
      EXPECT_LT(worst, tolerance) << "scale " << scale;
    }
  }
}

TEST(GreenCoordinates, NonConvexCageWithPointsInExtendedFacePlanes) {
  // An L of three unit cubes: the plane of the top face of one arm passes
  // through the inside of the other, and so do the lines of many edges.
  const TriMesh cage = test::voxelShapeCage({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  std::vector<Eigen::Vector3d> points{{0.5, 1.0, 0.5}, {1.0, 0.5, 0.5}, {0.5, 1.0, 1e-9}, {0.25, 1.0, 0.5},
                                      {0.5, 0.5, 0.5}, {1.5, 0.5, 0.5}, {0.5, 1.5, 0.5}, {0.999999999, 0.5, 0.5}};
  std::mt19937 rng(3);
  const auto random = randomInteriorPoints(cage, 50, 1e-3, rng);
  points.insert(points.end(), random.begin(), random.end());
  const GreenCoordinates gc = greenCoordinates(cage, points);
  double worst = 0;
  for (std::size_t p = 0; p < points.size(); ++p) {
    ASSERT_GT(cageWindingNumber(cage, points[p]), 0.5) << p;
    worst = std::max(worst, (reproduce(gc, cage, Eigen::Index(p)) - points[p]).norm());
  }
  RecordProperty("l_shape_error", sci(worst));
  // (0.5, 1, 1e-9) lies 1e-9 from a cage edge: ~1e-11 there, 1e-15 elsewhere.
  EXPECT_LT(worst, 1e-10);
}

TEST(GreenCoordinates, DisplacementFormInEveryPrecision) {
  const TriMesh cage = bumpyCage(2, 150.0, 0.3, {400.0, -250.0, 900.0});
  const double size = cageSize(cage);
  std::mt19937 rng(9);
  const std::vector<Eigen::Vector3d> points = randomInteriorPoints(cage, 300, 0.01 * size, rng);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.6, Eigen::Vector3d(0.2, 1, 0.4).normalized()).toRotationMatrix();
  const Eigen::Vector3d shift(40.0, -20.0, 75.0);
  std::vector<Eigen::Vector3d> moved;
  for (const auto& v : cage.positions) moved.push_back(r * v + shift);
  double displacement = 0;
  for (const auto& p : points) displacement = std::max(displacement, (r * p + shift - p).norm());
  for (GreenPrecision precision : {GreenPrecision::Double, GreenPrecision::Float, GreenPrecision::Half}) {
    const GreenCoordinates gc = greenCoordinates(cage, points, precision);
    std::vector<Eigen::Vector3d> out(points.size());
    // The rest cage gives the points back exactly.
    applyGreenCoordinates(gc, greenCageDisplacement(cage, cage.positions, gc.stride()), out, points);
    for (std::size_t p = 0; p < points.size(); ++p) ASSERT_EQ(out[p], points[p]);
    applyGreenCoordinates(gc, greenCageDisplacement(cage, moved, gc.stride()), out, points);
    double worst = 0;
    for (std::size_t p = 0; p < points.size(); ++p) worst = std::max(worst, (out[p] - (r * points[p] + shift)).norm());
    const char* tag = precision == GreenPrecision::Double ? "double" : precision == GreenPrecision::Float ? "float" : "half";
    RecordProperty(std::string(tag) + "_error_over_displacement", sci(worst / displacement));
    const double tolerance = precision == GreenPrecision::Double ? 1e-12 : precision == GreenPrecision::Float ? 1e-6 : 2e-3;
    EXPECT_LT(worst / displacement, tolerance) << tag;
  }
}

TEST(GreenCoordinates, WindingNumberClassifiesPoints) {
  const TriMesh cage = bumpyCage(2, 1.0, 0.3, Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> points;
  std::vector<std::uint8_t> expected;
  // Along rays from the centre (the cage is star-shaped): radius fractions
  // just inside and just outside the surface at that direction.
  for (std::size_t i = 0; i < cage.vertexCount(); i += 3) {
    const Eigen::Vector3d& v = cage.positions[i];
    for (double f : {0.3, 0.999, 1.001, 2.0}) {
      points.push_back(f * v);
      expected.push_back(f < 1.0 ? 1 : 0);
    }
  }
  const auto inside = insideCage(cage, points);
  for (std::size_t p = 0; p < points.size(); ++p) EXPECT_EQ(inside[p], expected[p]) << p;
  EXPECT_NEAR(cageWindingNumber(cage, Eigen::Vector3d::Zero()), 1.0, 1e-12);
  EXPECT_NEAR(cageWindingNumber(cage, Eigen::Vector3d(5, 5, 5)), 0.0, 1e-12);
}

TEST(GreenCoordinates, RejectsOpenCage) {
  TriMesh cage = test::icosphere(1);
  cage.triangles.pop_back();
  const std::vector<Eigen::Vector3d> points{Eigen::Vector3d::Zero()};
  try {
    greenCoordinates(cage, points);
    FAIL() << "an open cage was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not closed"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace vox
