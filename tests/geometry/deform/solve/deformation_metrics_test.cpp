// The per-tet measures of the refinement run on the parallel loop: the same
// bytes on one thread and on two, and a degenerate tet named the same way.

#include "geometry/deform/solve/deformation_metrics.h"

#include "geometry/error.h"
#include "geometry/parallel.h"
#include "geometry/voxel_tetrahedralization.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

namespace vox {
namespace {

// 12,288 tets (three ranges of the parallel loop's grain), bent smoothly.
TetMesh block() {
  GridGeometry g;
  g.dims = {16, 16, 8};
  return tetrahedralizeVoxels(LabelGrid(g, 1), {.includeBackground = false});
}

std::vector<Eigen::Vector3d> bent(const TetMesh& mesh) {
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector3d& p : mesh.positions) out.emplace_back(p.x(), p.y() + std::sin(0.3 * p.x()) * p.z(), p.z());
  return out;
}

template <typename T>
bool sameBytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

TEST(DeformationMetrics, TheSameBytesOnOneThreadAndOnTwo) {
  const TetMesh mesh = block();
  const std::vector<Eigen::Vector3d> deformed = bent(mesh);
  std::vector<Eigen::Matrix3d> basis[2];
  std::vector<double> error[2];
  for (const int threads : {1, 2}) {
    const ScopedWorkerThreads scope(threads);
    basis[threads - 1] = basisChanges(mesh, deformed);
    error[threads - 1] = tetDeformationError(mesh, deformed);
  }
  EXPECT_TRUE(sameBytes(basis[0], basis[1]));
  EXPECT_TRUE(sameBytes(error[0], error[1]));
  double largest = 0.0;
  for (const double e : error[0]) largest = std::max(largest, e);
  EXPECT_GT(largest, 0.01);
}

// Two degenerate tets in different ranges: the error names the first.
TEST(DeformationMetrics, ADegenerateTetIsTheFirstOneWhateverTheThreads) {
  TetMesh mesh = block();
  for (const std::size_t t : {std::size_t(5000), std::size_t(9000)}) mesh.tets[t][1] = mesh.tets[t][0];
  const std::vector<Eigen::Vector3d> deformed = bent(mesh);
  for (const int threads : {1, 2, 3}) {
    const ScopedWorkerThreads scope(threads);
    try {
      basisChanges(mesh, deformed);
      ADD_FAILURE() << threads << " threads: no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("tet 5000 is degenerate"), std::string::npos) << threads << ": " << e.what();
    }
  }
}

}  // namespace
}  // namespace vox
