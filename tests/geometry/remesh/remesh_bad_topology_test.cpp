// Tet meshes that pass the reader and every per-tet check but are not an
// embedding (issue 40): one tet overlapping its neighbours, a tet folded over
// among positive ones, a duplicated tet, a third tet on a face, an edge whose
// tets form two cycles. Each is refused before any remeshing, in one line
// naming the tet and its vertices. Before the checks the first made
// `remesh` split the same edge forever; the CLI runs here under `timeout`, so
// a regression fails the test instead of hanging it.
// The meshes are the seeds in tests/fuzz/corpus/remesh (make_bad_topology.py).

#include "geometry/error.h"
#include "geometry/io/mesh_io.h"
#include "geometry/remesh/remesh_complex.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

namespace vox::remesh {
namespace {

struct BadMesh {
  const char* name;
  const char* tet;  // what the message must name: "tet N (vertices ..."
};

std::string corpusPath(const std::string& name) { return test::assetPath("../tests/fuzz/corpus/remesh/" + name + ".mesh"); }

class RemeshBadTopology : public ::testing::TestWithParam<BadMesh> {};

TEST_P(RemeshBadTopology, RefusedByTheComplexNamingTheTet) {
  const std::string path = corpusPath(GetParam().name);
  TetMesh mesh = readTetMesh(path);
  orientPositively(mesh);
  checkNoFlatTets(mesh, path);
  try {
    RemeshComplex complex(mesh, path);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
    EXPECT_NE(message.find(GetParam().tet), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST_P(RemeshBadTopology, CommandRefusesInOneLineAndWritesNothing) {
  VOX_REQUIRE_VOXMORPH();
  const std::string path = corpusPath(GetParam().name);
  const std::string out = test::tempDir() + "/out.mesh";
  // `timeout` bounds the run: the remesher used to spin on these (exit 124).
  const auto run = test::runCommand("timeout 20 " + test::quote(test::voxmorphBinary()) + " remesh " + test::quote(path) +
                                    " -l 4 -q -o " + test::quote(out));
  EXPECT_EQ(run.exitCode, 1) << run.err;
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
  EXPECT_NE(run.err.find(path + ": "), std::string::npos) << run.err;
  EXPECT_NE(run.err.find(GetParam().tet), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(out));
}

INSTANTIATE_TEST_SUITE_P(Corpus, RemeshBadTopology,
                         ::testing::Values(BadMesh{"overlapping_tet", "tet 101 (vertices 18, 34, 44, 39)"}, BadMesh{"folded_tet", "tet 77 (vertices 28, 26, 40, 11)"},
                                           BadMesh{"duplicated_tet", "tet 180 (vertices 28, 40, 11, 41)"},
                                           BadMesh{"face_in_three_tets", "tet 180 (vertices 40, 11, 28, 41)"},
                                           BadMesh{"edge_star_in_two_cycles", "tet 77 (vertices 28, 26, 11, 40)"},
                                           BadMesh{"overlapping_parts_along_an_edge", "tet 0 (vertices 3, 0, 1, 13)"}),
                         [](const ::testing::TestParamInfo<BadMesh>& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace vox::remesh
