#include "geometry/deform/solve/injective_solve.h"
#include "geometry/error.h"
#include "geometry/voxel_tetrahedralization.h"

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace vox {
namespace {

// A bar of nx x ny x nz unit voxels (six tets each), x from -0.5 to
// nx - 0.5. Its first and last `endLength` voxels are held: the first
// fixed, the last turned about the z axis through the bar's centre line at
// mid-length (a hinge, as an elbow), the voxels between are free tissue.
struct Bar {
  TetMesh mesh;
  std::vector<std::int32_t> constrained;
  std::vector<std::int32_t> motionOf;  // 0 fixed, 1 turned
  Eigen::Vector3d hinge;
  double length = 0.0;

  // coreHalfWidth >= 0: only the vertices within that distance of the
  // centre line (in y and z) of each end are held: a bone inside a limb.
  Bar(int nx, int ny, int nz, int endLength, double coreHalfWidth = -1.0) {
    GridGeometry g;
    g.dims = {nx, ny, nz};
    mesh = tetrahedralizeVoxels(LabelGrid(g, 1), {.includeBackground = false});
    length = nx;
    hinge = Eigen::Vector3d(0.5 * (nx - 1), 0.5 * (ny - 1), 0.5 * (nz - 1));
    for (std::size_t v = 0; v < mesh.vertexCount(); ++v) {
      const double x = mesh.positions[v].x() + 0.5;
      const Eigen::Vector3d& p = mesh.positions[v];
      if (coreHalfWidth >= 0.0 && (std::abs(p.y() - hinge.y()) > coreHalfWidth + 1e-9 || std::abs(p.z() - hinge.z()) > coreHalfWidth + 1e-9))
        continue;
      if (x <= endLength + 1e-9) {
        constrained.push_back(std::int32_t(v));
        motionOf.push_back(0);
      } else if (x >= nx - endLength - 1e-9) {
        constrained.push_back(std::int32_t(v));
        motionOf.push_back(1);
      }
    }
  }

  // The turned end's motion: degrees about z through the hinge.
  Eigen::Isometry3d turn(double degrees) const {
    Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
    m.translate(hinge);
    m.rotate(Eigen::AngleAxisd(degrees * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ()));
    m.translate(-hinge);
    return m;
  }
  std::vector<Eigen::Isometry3d> motions(double degrees) const { return {Eigen::Isometry3d::Identity(), turn(degrees)}; }
  std::vector<Eigen::Vector3d> targets(double degrees) const {
    const auto m = motions(degrees);
    std::vector<Eigen::Vector3d> out(constrained.size());
    for (std::size_t k = 0; k < constrained.size(); ++k)
      out[k] = m[std::size_t(motionOf[k])] * mesh.positions[std::size_t(constrained[k])];
    return out;
  }
};

std::size_t invertedTets(const TetMesh& mesh, const std::vector<Eigen::Vector3d>& positions) {
  std::size_t count = 0;
  for (const Tet& t : mesh.tets)
    if (!(signedVolume(positions, t) > 0.0)) ++count;
  return count;
}

double totalVolume(const TetMesh& mesh, const std::vector<Eigen::Vector3d>& positions) {
  double sum = 0.0;
  for (const Tet& t : mesh.tets) sum += signedVolume(positions, t);
  return sum;
}

InjectiveSolveResult bendBar(const Bar& bar, double degrees, const InjectiveSolveOptions& options) {
  const auto motions = bar.motions(degrees);
  return solveInjective(bar.mesh.positions, bar.mesh.tets, bar.constrained,
                        rigidStepTargets(bar.mesh.positions, bar.constrained, bar.motionOf, motions), options);
}

void expectInjectiveBend(const Bar& bar, double degrees, int steps) {
  InjectiveSolveOptions options;
  options.steps = steps;
  const InjectiveSolveResult result = bendBar(bar, degrees, options);
  SCOPED_TRACE(std::to_string(degrees) + " degrees in " + std::to_string(steps) + " steps");
  EXPECT_EQ(result.invertedTets, 0u);
  EXPECT_EQ(invertedTets(bar.mesh, result.positions), 0u);
  EXPECT_GT(result.minRelativeVolume, 0.0);
  ASSERT_EQ(result.steps.size(), std::size_t(steps));
  for (std::size_t s = 0; s < result.steps.size(); ++s) {
    const InjectiveStepReport& step = result.steps[s];
    EXPECT_TRUE(step.reachedTargets) << "step " << s;
    EXPECT_GT(step.minRelativeVolume, 0.0) << "step " << s;
    // Once the bones sit at their targets, no iteration raises the energy.
    for (std::size_t i = 1; i < step.energies.size(); ++i) EXPECT_LE(step.energies[i], step.energies[i - 1]) << "step " << s;
  }
  EXPECT_TRUE(result.converged);
  // The held ends are where their motions put them.
  const auto targets = bar.targets(degrees);
  for (std::size_t k = 0; k < bar.constrained.size(); ++k)
    EXPECT_EQ(result.positions[std::size_t(bar.constrained[k])], targets[k]);
  std::printf("[ bar %.0f deg ] %d iterations, energy %.4f, min det J %.4f, volume %+.2f %%\n", degrees,
              result.iterations, result.energy, result.minRelativeVolume,
              100.0 * (totalVolume(bar.mesh, result.positions) / totalVolume(bar.mesh, bar.mesh.positions) - 1.0));
}

TEST(InjectiveSolve, BarBentNinetyDegreesInStepsInvertsNoTet) { expectInjectiveBend(Bar(24, 4, 4, 6), 90.0, 6); }

TEST(InjectiveSolve, BarBentOneHundredTwentyDegreesInStepsInvertsNoTet) { expectInjectiveBend(Bar(24, 4, 4, 6), 120.0, 8); }

TEST(InjectiveSolve, ScrewInterpolationTurnsAboutTheJointCentre) {
  const Bar bar(24, 4, 4, 6);
  const Eigen::Isometry3d motion = bar.turn(120.0);
  for (const double s : {0.25, 0.5, 1.0}) {
    const Eigen::Isometry3d partial = screwInterpolate(motion, s);
    EXPECT_NEAR((partial * bar.hinge - bar.hinge).norm(), 0.0, 1e-12);
    const Eigen::AngleAxisd angle(partial.linear());
    EXPECT_NEAR(angle.angle(), s * 120.0 * std::numbers::pi / 180.0, 1e-12);
  }
  EXPECT_TRUE(screwInterpolate(motion, 1.0).isApprox(motion, 1e-12));
  EXPECT_TRUE(screwInterpolate(motion, 0.0).isApprox(Eigen::Isometry3d::Identity(), 1e-12));
  Eigen::Isometry3d slide = Eigen::Isometry3d::Identity();
  slide.translation() = Eigen::Vector3d(1, 2, 3);
  EXPECT_TRUE(screwInterpolate(slide, 0.5).translation().isApprox(Eigen::Vector3d(0.5, 1, 1.5)));
}

// One least-squares solve: the displacement minimizing the tets' Dirichlet
// energy (rest volume times the barycentric gradients' dot products) with
// the held vertices at their targets, i.e. sum |t| ||J_t - I||^2: the first
// global step of ARAP from rest.
std::vector<Eigen::Vector3d> leastSquaresSolve(const Bar& bar, double degrees) {
  const std::size_t n = bar.mesh.vertexCount();
  std::vector<int> slot(n, -1);
  for (const std::int32_t v : bar.constrained) slot[std::size_t(v)] = -2;
  int freeCount = 0;
  for (std::size_t v = 0; v < n; ++v)
    if (slot[v] == -1) slot[v] = freeCount++;
  std::vector<Eigen::Vector3d> solved = bar.mesh.positions;
  const auto targets = bar.targets(degrees);
  for (std::size_t k = 0; k < bar.constrained.size(); ++k) solved[std::size_t(bar.constrained[k])] = targets[k];
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(freeCount, 3);
  for (const Tet& t : bar.mesh.tets) {
    Eigen::Matrix3d edges;
    for (int a = 0; a < 3; ++a) edges.col(a) = bar.mesh.positions[std::size_t(t[std::size_t(a) + 1])] - bar.mesh.positions[std::size_t(t[0])];
    const Eigen::Matrix3d inv = edges.inverse();
    std::array<Eigen::Vector3d, 4> g;
    for (int a = 0; a < 3; ++a) g[std::size_t(a) + 1] = inv.row(a).transpose();
    g[0] = -(g[1] + g[2] + g[3]);
    const double volume = signedVolume(bar.mesh.positions, t);
    for (int a = 0; a < 4; ++a) {
      const int row = slot[std::size_t(t[std::size_t(a)])];
      if (row < 0) continue;
      for (int b = 0; b < 4; ++b) {
        const double k = volume * g[std::size_t(a)].dot(g[std::size_t(b)]);
        const int col = slot[std::size_t(t[std::size_t(b)])];
        if (col >= 0) entries.emplace_back(row, col, k);
        else rhs.row(row) -= k * (solved[std::size_t(t[std::size_t(b)])] - bar.mesh.positions[std::size_t(t[std::size_t(b)])]).transpose();
      }
    }
  }
  Eigen::SparseMatrix<double> laplacian(freeCount, freeCount);
  laplacian.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(laplacian);
  const Eigen::MatrixXd x = ldlt.solve(rhs);
  for (std::size_t v = 0; v < n; ++v)
    if (slot[v] >= 0) solved[v] += x.row(slot[v]).transpose();
  return solved;
}

// A limb: 24 x 6 x 6 voxels, a bone (the 3 x 3 vertices around the centre
// line) in each end's 8 voxels, the rest soft tissue, the lower bone turned
// 120 degrees about the hinge. The free vertices placed by the two obvious
// linear methods: blending the two bones' motions linearly along the limb
// (linear interpolation of the rigid motions), and one least-squares solve
// of the tets' Dirichlet energy (the first global step of ARAP). Both
// invert tets in the crease; the injective solve does not.
TEST(InjectiveSolve, LinearMethodsInvertTetsWhereTheInjectiveSolveDoesNot) {
  const Bar bar(24, 6, 6, 8, 1.0);
  const double degrees = 120.0;
  const auto motions = bar.motions(degrees);

  std::vector<Eigen::Vector3d> blended = bar.mesh.positions;
  for (Eigen::Vector3d& p : blended) {
    const double s = std::clamp((p.x() + 0.5 - 8.0) / (bar.length - 16.0), 0.0, 1.0);
    p = (1.0 - s) * p + s * (motions[1] * p);
  }
  const std::size_t blendInverted = invertedTets(bar.mesh, blended);

  const std::vector<Eigen::Vector3d> solved = leastSquaresSolve(bar, degrees);
  const std::size_t solveInverted = invertedTets(bar.mesh, solved);

  InjectiveSolveOptions options;
  options.steps = 8;
  const InjectiveSolveResult injective = bendBar(bar, degrees, options);
  std::printf("[ limb 120 deg ] inverted tets: linear blend %zu, one least-squares solve %zu, injective solve %zu "
              "(min det J %.4f, %d iterations)\n",
              blendInverted, solveInverted, injective.invertedTets, injective.minRelativeVolume, injective.iterations);
  EXPECT_GT(blendInverted, 0u);
  EXPECT_GT(solveInverted, 0u);
  EXPECT_EQ(injective.invertedTets, 0u);
  EXPECT_EQ(invertedTets(bar.mesh, injective.positions), 0u);
  EXPECT_GT(injective.minRelativeVolume, 0.0);
  EXPECT_TRUE(injective.converged);
}

// The limb's bone turned to 100 degrees in frames of 1.67 degrees, two
// iterations each, then held: every frame injective, the bones at their
// targets in most frames and at the end.
TEST(InjectiveSolve, InteractiveFramesStayInjective) {
  const Bar bar(24, 6, 6, 8, 1.0);
  InjectiveSolver solver;
  InjectiveSolveOptions options;
  options.frameIterations = 2;
  solver.precompute(bar.mesh.positions, bar.mesh.tets, bar.constrained, {}, {}, options);
  double least = 1.0;
  int reached = 0;
  const int frames = 60;
  for (int f = 1; f <= frames; ++f) {
    const double degrees = 100.0 * double(f) / double(frames);
    const InjectiveStepReport report = solver.frame(bar.targets(degrees));
    least = std::min(least, report.minRelativeVolume);
    reached += report.reachedTargets ? 1 : 0;
    ASSERT_GT(report.minRelativeVolume, 0.0) << "frame " << f;
    ASSERT_EQ(invertedTets(bar.mesh, solver.positions()), 0u) << "frame " << f;
  }
  // Held still, a few more frames settle the bones at their targets.
  for (int f = 0; f < 10; ++f) least = std::min(least, solver.frame(bar.targets(100.0)).minRelativeVolume);
  const auto targets = bar.targets(100.0);
  for (std::size_t k = 0; k < bar.constrained.size(); ++k)
    EXPECT_EQ(solver.positions()[std::size_t(bar.constrained[k])], targets[k]);
  EXPECT_EQ(invertedTets(bar.mesh, solver.positions()), 0u);
  std::printf("[ frames ] %d of %d frames reached the targets, min det J %.4f\n", reached, frames, least);
  EXPECT_GT(reached, frames / 2);
}

// The volume term holds the volume: within 1 % with the default weight, for
// the bar at 90 degrees and the limb at 120, closer than without it.
TEST(InjectiveSolve, VolumeTermKeepsTheTotalVolume) {
  const Bar bar(24, 4, 4, 6);
  const double rest = totalVolume(bar.mesh, bar.mesh.positions);
  InjectiveSolveOptions with;
  with.steps = 6;
  InjectiveSolveOptions without = with;
  without.volumeWeight = 0.0;
  const double changeWith = std::abs(totalVolume(bar.mesh, bendBar(bar, 90.0, with).positions) / rest - 1.0);
  const double changeWithout = std::abs(totalVolume(bar.mesh, bendBar(bar, 90.0, without).positions) / rest - 1.0);
  const Bar limb(24, 6, 6, 8, 1.0);
  const double limbRest = totalVolume(limb.mesh, limb.mesh.positions);
  with.steps = 8;
  const double limbChange = std::abs(totalVolume(limb.mesh, bendBar(limb, 120.0, with).positions) / limbRest - 1.0);
  std::printf("[ volume ] |change|: bar at 90 deg %.3f %% (without the term %.3f %%), limb at 120 deg %.3f %%\n",
              100.0 * changeWith, 100.0 * changeWithout, 100.0 * limbChange);
  EXPECT_LT(changeWith, 0.01);
  EXPECT_LT(limbChange, 0.01);
  EXPECT_LT(changeWith, changeWithout);
}

// Meshes too large to factorize the SLIM system every iteration solve it by
// conjugate gradients preconditioned by the rest system: forced here on the
// bar, the result is injective and close to the factorized solve's.
TEST(InjectiveSolve, ConjugateGradientPathAgreesWithTheFactorizedSolve) {
  const Bar bar(24, 4, 4, 6);
  InjectiveSolveOptions options;
  options.steps = 6;
  const InjectiveSolveResult direct = bendBar(bar, 90.0, options);
  options.directSolveLimit = 0;
  const InjectiveSolveResult iterative = bendBar(bar, 90.0, options);
  EXPECT_EQ(iterative.invertedTets, 0u);
  EXPECT_GT(iterative.minRelativeVolume, 0.0);
  EXPECT_TRUE(iterative.converged);
  double largest = 0.0;
  for (std::size_t v = 0; v < bar.mesh.vertexCount(); ++v)
    largest = std::max(largest, (iterative.positions[v] - direct.positions[v]).norm());
  std::printf("[ cg ] %d iterations (factorized: %d), energy %.5f (%.5f), largest distance %.4f\n", iterative.iterations,
              direct.iterations, iterative.energy, direct.energy, largest);
  EXPECT_NEAR(iterative.energy, direct.energy, 1e-4 * direct.energy);
  EXPECT_LT(largest, 0.05);  // voxels of 1
}

// Soft targets pull free vertices: the bar's middle, free, pulled sideways.
TEST(InjectiveSolve, SoftTargetsPullFreeVertices) {
  const Bar bar(24, 4, 4, 6);
  std::vector<std::int32_t> soft;
  std::vector<Eigen::Vector3d> pulled;
  for (std::size_t v = 0; v < bar.mesh.vertexCount(); ++v)
    if (std::abs(bar.mesh.positions[v].x() - 11.5) < 1e-9) {
      soft.push_back(std::int32_t(v));
      pulled.push_back(bar.mesh.positions[v] + Eigen::Vector3d(0, 1.0, 0));
    }
  const std::vector<double> weights(soft.size(), 10.0);
  InjectiveSolver solver;
  solver.precompute(bar.mesh.positions, bar.mesh.tets, bar.constrained, soft, weights);
  const InjectiveStepReport report = solver.solveStep(bar.targets(0.0), pulled);
  EXPECT_TRUE(report.converged);
  double moved = 0.0;
  for (const std::int32_t v : soft) moved += solver.positions()[std::size_t(v)].y() - bar.mesh.positions[std::size_t(v)].y();
  moved /= double(soft.size());
  EXPECT_GT(moved, 0.3);
  EXPECT_LT(moved, 1.0);
  EXPECT_EQ(invertedTets(bar.mesh, solver.positions()), 0u);
}

TEST(InjectiveSolve, IdentityPoseKeepsTheRest) {
  const Bar bar(12, 3, 3, 3);
  InjectiveSolveOptions options;
  options.steps = 2;
  const InjectiveSolveResult result = bendBar(bar, 0.0, options);
  for (std::size_t v = 0; v < bar.mesh.vertexCount(); ++v)
    EXPECT_LT((result.positions[v] - bar.mesh.positions[v]).norm(), 1e-9);
  EXPECT_NEAR(result.minRelativeVolume, 1.0, 1e-9);
  EXPECT_TRUE(result.converged);
  // At rest every tet's symmetric Dirichlet term is 6 and the volume term 0.
  InjectiveSolver solver;
  solver.precompute(bar.mesh.positions, bar.mesh.tets, bar.constrained);
  EXPECT_NEAR(solver.energy(bar.mesh.positions), 6.0, 1e-9);
  std::vector<Eigen::Vector3d> flat = bar.mesh.positions;
  const Tet& t = bar.mesh.tets[0];
  flat[std::size_t(t[3])] = (flat[std::size_t(t[0])] + flat[std::size_t(t[1])] + flat[std::size_t(t[2])]) / 3.0;
  EXPECT_EQ(solver.energy(flat), std::numeric_limits<double>::infinity());
}

void expectInputError(const std::function<void()>& call, const std::string& fragment) {
  try {
    call();
    ADD_FAILURE() << "no InputError for " << fragment;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  }
}

TEST(InjectiveSolve, BadInputIsRefusedWithAClearMessage) {
  const Bar bar(6, 2, 2, 1);
  const auto& points = bar.mesh.positions;
  const auto& tets = bar.mesh.tets;
  InjectiveSolver solver;
  expectInputError([&] {
    std::vector<std::int32_t> c = bar.constrained;
    c.push_back(std::int32_t(points.size()));
    solver.precompute(points, tets, c);
  }, "constrained vertex " + std::to_string(points.size()) + " is out of range");
  expectInputError([&] {
    std::vector<std::int32_t> c = bar.constrained;
    c.push_back(c.front());
    solver.precompute(points, tets, c);
  }, "is repeated");
  expectInputError([&] {
    std::vector<Tet> t = tets;
    std::swap(t[3][0], t[3][1]);
    solver.precompute(points, t, bar.constrained);
  }, "transfer mesh: tet 3 is inverted at rest");
  expectInputError([&] {
    std::vector<Eigen::Vector3d> p = points;
    const Tet& t = tets[5];
    p[std::size_t(t[3])] = (p[std::size_t(t[0])] + p[std::size_t(t[1])] + p[std::size_t(t[2])]) / 3.0;  // flat
    solver.precompute(p, tets, bar.constrained);
  }, "is degenerate at rest");
  expectInputError([&] { solver.precompute(points, tets, {}); }, "has no constrained or soft vertex");
  expectInputError([&] {
    std::vector<Tet> t = tets;
    t[0][2] = -4;
    solver.precompute(points, t, bar.constrained);
  }, "tet 0 refers to vertex -4");
  expectInputError([&] {
    const std::vector<std::int32_t> soft{0};
    const std::vector<double> weights{-1.0};
    solver.precompute(points, tets, bar.constrained, soft, weights);
  }, "weight that is not finite and positive");
  solver.precompute(points, tets, bar.constrained);
  expectInputError([&] { solver.solveStep(std::vector<Eigen::Vector3d>(1)); }, "targets for");
  // InputError is the project's std::runtime_error; callers that catch
  // std::exception see it too.
  EXPECT_THROW(solver.precompute(points, tets, std::vector<std::int32_t>{-1}), std::runtime_error);
}

}  // namespace
}  // namespace vox
