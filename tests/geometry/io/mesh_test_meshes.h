#pragma once
// Meshes and checks shared by the mesh and surface format tests.

#include "geometry/error.h"
#include "geometry/synth.h"
#include "geometry/tet_mesh.h"
#include "geometry/voxel_tetrahedralization.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <sys/mman.h>
#include <unistd.h>

namespace vox::test {

// The junction sphere (labels 1..5) in its background box (label 0): 10368
// tets, 2197 vertices at half-integer coordinates (exact in any format).
inline TetMesh junctionSphereMesh() { return tetrahedralizeVoxels(synthesize(SynthKind::JunctionSphere, 12)); }

// The same connectivity with coordinates that need all 17 significant
// digits, and labels that include the dummy label -1 and the int32 extremes
// next to the sphere's 0..5.
inline TetMesh labeledMesh() {
  TetMesh mesh = junctionSphereMesh();
  for (std::size_t v = 0; v < mesh.vertexCount(); ++v) {
    Eigen::Vector3d& p = mesh.positions[v];
    p = p * 0.1 + Eigen::Vector3d(1e-4 * std::sin(double(v)), 1e-4 * std::cos(double(v)), 1.0 / 3.0);
  }
  for (std::size_t t = 0; t < mesh.tetCount(); t += 97) mesh.labels[t] = kDummyLabel;
  mesh.labels[5] = 2147483647;
  mesh.labels[6] = -2147483647 - 1;
  return mesh;
}

inline void expectSameMesh(const TetMesh& expected, const TetMesh& actual) {
  ASSERT_EQ(expected.vertexCount(), actual.vertexCount());
  ASSERT_EQ(expected.tetCount(), actual.tetCount());
  for (std::size_t v = 0; v < expected.vertexCount(); ++v)
    ASSERT_EQ(expected.positions[v], actual.positions[v]) << "vertex " << v;
  for (std::size_t t = 0; t < expected.tetCount(); ++t) {
    ASSERT_EQ(expected.tets[t], actual.tets[t]) << "tet " << t;
    ASSERT_EQ(expected.labels[t], actual.labels[t]) << "tet " << t;
  }
}

// labeledMesh() with names for some of its labels: spaces, a comma, XML
// and quote characters, and the int32 extreme.
inline TetMesh namedMesh() {
  TetMesh mesh = labeledMesh();
  mesh.labelNames = {{1, "Adrenal, left"}, {2, "Brain <grey> & \"white\""}, {3, "Liver"}, {2147483647, "Skin"}};
  return mesh;
}

// `read` must throw InputError whose message starts with the path and
// contains `fault`.
inline void expectInputError(const std::function<void()>& read, const std::string& path, const std::string& fault) {
  try {
    read();
    ADD_FAILURE() << "no InputError for " << path << " (expected: " << fault << ")";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
    EXPECT_NE(what.find(fault), std::string::npos) << "message: " << what << "\nexpected fault: " << fault;
  }
}

// An in-memory file (memfd) for tests that read thousands of variants of a
// small file: rewriting a file on disk costs more than the reads. It is
// reached through a symlink named `name` in `dir`, so readers see the
// extension.
class MemoryFile {
public:
  MemoryFile(const std::string& dir, const std::string& name) : fd_(::memfd_create("mesh", 0)), path_(dir + "/" + name) {
    std::filesystem::create_symlink("/proc/" + std::to_string(::getpid()) + "/fd/" + std::to_string(fd_), path_);
  }
  ~MemoryFile() {
    std::filesystem::remove(path_);
    ::close(fd_);
  }
  const std::string& set(const std::string& bytes) {
    EXPECT_EQ(::ftruncate(fd_, 0), 0);
    EXPECT_EQ(::pwrite(fd_, bytes.data(), bytes.size(), 0), ssize_t(bytes.size()));
    return path_;
  }

private:
  int fd_;
  std::string path_;
};

}  // namespace vox::test
