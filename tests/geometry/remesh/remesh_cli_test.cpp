// `voxmorph mesh` and `voxmorph remesh` end to end: files written, read back
// by meshio, byte-identical on a second run, the JSON report, bad input.

#include "geometry/io/mesh_io.h"
#include "geometry/io/png_io.h"
#include "geometry/remesh/mesh_topology.h"
#include "geometry/voxel_tetrahedralization.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <tuple>
#include <vector>

namespace vox::remesh {
namespace {

namespace fs = std::filesystem;
using test::quote;
using test::runCommand;

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string voxmorph(const std::string& args) { return quote(test::voxmorphBinary()) + " " + args; }

TEST(RemeshCli, MeshesAGridDeterministicallyWithAReport) {
  const std::string dir = test::tempDir();
  const std::string grid = dir + "/junctions.nii.gz";
  ASSERT_EQ(runCommand(voxmorph("synth junctions --size 20 -o " + quote(grid))).exitCode, 0);
  for (const char* name : {"a.mesh", "b.mesh"}) {
    const auto r = runCommand(voxmorph("mesh " + quote(grid) + " -l 2.5 -q -o " + quote(dir + "/" + name) +
                                       " --report " + quote(dir + "/" + name + ".json")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("topology             preserved"), std::string::npos) << r.out;
  }
  const std::string a = slurp(dir + "/a.mesh");
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(a, slurp(dir + "/b.mesh")) << "two runs differ";

  const auto report = nlohmann::json::parse(slurp(dir + "/a.mesh.json"));
  EXPECT_TRUE(report["topology"]["preserved"].get<bool>());
  EXPECT_EQ(report["inverted_tets"].get<int>(), 0);
  EXPECT_GT(report["dihedral_degrees"]["min"].get<double>(), 10.0);
  EXPECT_EQ(report["labels"].size(), 5u);
  EXPECT_LE(report["tets_under_10_degrees"].get<std::size_t>(), report["tets_under_15_degrees"].get<std::size_t>());
  for (const auto& l : report["labels"]) {
    const auto& mm = l["interface_distance_mm"];
    const auto& rel = l["interface_distance_over_l"];
    for (const char* way : {"output_to_input", "input_to_output"}) {
      EXPECT_GT(mm[way].get<double>(), 0.0) << l["label"] << " " << way;
      EXPECT_NEAR(rel[way].get<double>(), mm[way].get<double>() / 2.5, 1e-12) << l["label"] << " " << way;
    }
  }
  // Six angles per output tet in the histogram, and its chart beside the JSON.
  std::size_t angles = 0, under10 = 0;
  const auto& counts = report["dihedral_histogram"]["counts"];
  ASSERT_EQ(counts.size(), 180u);
  for (std::size_t i = 0; i < counts.size(); ++i) {
    angles += counts[i].get<std::size_t>();
    if (i < 10) under10 += counts[i].get<std::size_t>();
  }
  EXPECT_EQ(angles, 6 * report["tets"]["output"].get<std::size_t>());
  EXPECT_EQ(under10, 0u) << "the report's minimum is over 10 degrees";
  const RgbImage chart = readPng(dir + "/a.mesh_dihedral.png");
  EXPECT_EQ(chart.width, 736);
  EXPECT_EQ(chart.height, 216);
  EXPECT_GT(countNotBackground(chart, Rgb{255, 255, 255}), 1000u);

  // The written mesh holds what the report says, and only domain tets.
  const TetMesh mesh = readTetMesh(dir + "/a.mesh");
  EXPECT_EQ(mesh.tetCount(), report["tets"]["output"].get<std::size_t>());
  for (std::int32_t l : mesh.labels) ASSERT_GT(l, 0);
}

TEST(RemeshCli, RemeshesAMeshIntoEveryFormat) {
  const std::string dir = test::tempDir();
  const std::string grid = dir + "/spheres.nii.gz";
  ASSERT_EQ(runCommand(voxmorph("synth spheres --size 16 -o " + quote(grid))).exitCode, 0);
  ASSERT_EQ(runCommand(voxmorph("mesh " + quote(grid) + " -l 2 -q -o " + quote(dir + "/in.vtu"))).exitCode, 0);
  const MeshTopology before = computeMeshTopology(readTetMesh(dir + "/in.vtu"));
  for (const char* ext : {"mesh", "vtu", "msh"}) {
    const std::string out = dir + "/out." + ext;
    const auto r = runCommand(voxmorph("remesh " + quote(dir + "/in.vtu") + " -l 3 -q --iterations 4 -o " + quote(out)));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(compareTopology(before, computeMeshTopology(readTetMesh(out))).empty()) << ext;
  }
  if (!test::python().empty()) {
    const auto r = runCommand(quote(test::python()) + " -c " +
                              quote("import meshio; m = meshio.read('" + dir + "/out.vtu'); "
                                    "print(len(m.cells_dict['tetra']), sorted(set(m.cell_data['label'][0].tolist())))"));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("[1, 2, 3]"), std::string::npos) << r.out;
  }
}

TEST(RemeshCli, BadInputIsOneLineAndLeavesNoFile) {
  const std::string dir = test::tempDir();
  const std::string out = dir + "/out.mesh";
  // Missing input: failure, exit 1.
  auto r = runCommand(voxmorph("mesh " + quote(dir + "/missing.nii.gz") + " -l 2 -q -o " + quote(out)));
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("missing.nii.gz"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(out));
  // Usage errors: exit 2.
  EXPECT_EQ(runCommand(voxmorph("mesh " + quote(dir + "/x.nii.gz") + " -l 0 -o " + quote(out))).exitCode, 2);
  EXPECT_EQ(runCommand(voxmorph("mesh " + quote(dir + "/x.nii.gz") + " -l 2 -o " + quote(dir + "/out.obj"))).exitCode, 2);
  // A flat (zero-volume) tet is the input's fault: named, exit 1, nothing written.
  {
    std::ofstream bad(dir + "/flat.mesh");
    bad << "MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 0\n1 0 0 0\n0 1 0 0\n0.25 0.25 0 0\n"
           "Tetrahedra\n1\n1 2 3 4 1\nEnd\n";
  }
  r = runCommand(voxmorph("remesh " + quote(dir + "/flat.mesh") + " -l 1 -q -o " + quote(out)));
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("flat.mesh: tet 0 has zero volume"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// A NIfTI-1 file of float32 values: pixdim spacing, and the affine rows
// `sform` (3 x 4, sform_code 1) when given.
void writeFloatNifti(const std::string& path, int nx, int ny, int nz, float spacing, const std::vector<float>& values,
                     const std::vector<float>& sform = {}) {
  char header[352] = {};
  auto put = [&](int offset, auto value) { std::memcpy(header + offset, &value, sizeof value); };
  put(0, std::int32_t(348));
  const std::int16_t dims[8] = {3, std::int16_t(nx), std::int16_t(ny), std::int16_t(nz), 1, 1, 1, 1};
  std::memcpy(header + 40, dims, sizeof dims);
  put(70, std::int16_t(16));  // DT_FLOAT32
  put(72, std::int16_t(32));
  const float pixdim[8] = {1.0f, spacing, spacing, spacing, 1.0f, 1.0f, 1.0f, 1.0f};
  std::memcpy(header + 76, pixdim, sizeof pixdim);
  put(108, 352.0f);
  if (!sform.empty()) {
    put(254, std::int16_t(1));
    std::memcpy(header + 280, sform.data(), 12 * sizeof(float));
  }
  std::memcpy(header + 344, "n+1", 4);
  std::ofstream out(path, std::ios::binary);
  out.write(header, sizeof header);
  out.write(reinterpret_cast<const char*>(values.data()), std::streamsize(values.size() * sizeof(float)));
}

// Adaptive sizing (eq. 2.2): fewer tets than the uniform mesh at l_B, the
// same topology; a constant sizing grid gives the uniform mesh itself.
TEST(RemeshCli, AdaptiveSizingFromInterfacesOrAGrid) {
  const std::string dir = test::tempDir();
  const std::string grid = dir + "/spheres.nii.gz";
  ASSERT_EQ(runCommand(voxmorph("synth spheres --size 24 -o " + quote(grid))).exitCode, 0);
  auto r = runCommand(voxmorph("mesh " + quote(grid) + " -l 1.5 -q --no-distance -o " + quote(dir + "/uniform.mesh") +
                               " --report " + quote(dir + "/uniform.json")));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  r = runCommand(voxmorph("mesh " + quote(grid) + " --size-boundary 1.5 --size-interior 6 -q -o " +
                          quote(dir + "/adaptive.mesh") + " --report " + quote(dir + "/adaptive.json")));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("sizing field         adaptive, l from 1.5 to 6 mm"), std::string::npos) << r.out;
  const auto uniform = nlohmann::json::parse(slurp(dir + "/uniform.json"));
  const auto adaptive = nlohmann::json::parse(slurp(dir + "/adaptive.json"));
  EXPECT_TRUE(adaptive["topology"]["preserved"].get<bool>());
  EXPECT_EQ(adaptive["inverted_tets"].get<int>(), 0);
  EXPECT_EQ(adaptive["target_edge_length_mm"].get<double>(), 1.5);
  EXPECT_EQ(adaptive["sizing_field_mm"]["min"].get<double>(), 1.5);
  EXPECT_EQ(adaptive["sizing_field_mm"]["max"].get<double>(), 6.0);
  EXPECT_FALSE(uniform.contains("sizing_field_mm"));
  EXPECT_LT(adaptive["tets"]["output"].get<double>(), 0.8 * uniform["tets"]["output"].get<double>());

  // remesh: the field from the mesh's own interfaces.
  r = runCommand(voxmorph("remesh " + quote(dir + "/uniform.mesh") + " --size-boundary 1.5 --size-interior 6 -q " +
                          "--iterations 3 --no-distance -o " + quote(dir + "/remeshed.mesh") + " --report " +
                          quote(dir + "/remeshed.json")));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto remeshed = nlohmann::json::parse(slurp(dir + "/remeshed.json"));
  EXPECT_TRUE(remeshed["topology"]["preserved"].get<bool>());
  EXPECT_LT(remeshed["tets"]["output"].get<double>(), uniform["tets"]["output"].get<double>());

  // A grid of 2 mm everywhere, coarser than the label grid and elsewhere:
  // the same bytes as -l 2.
  writeFloatNifti(dir + "/two.nii", 5, 5, 5, 9.0f, std::vector<float>(125, 2.0f));
  ASSERT_EQ(runCommand(voxmorph("mesh " + quote(grid) + " -l 2 -q -o " + quote(dir + "/l2.mesh"))).exitCode, 0);
  r = runCommand(voxmorph("mesh " + quote(grid) + " --size-grid " + quote(dir + "/two.nii") + " -q -o " +
                          quote(dir + "/grid2.mesh")));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(slurp(dir + "/l2.mesh"), slurp(dir + "/grid2.mesh"));

  // Sampled in world mm through the grid's affine: two voxels of 12 mm,
  // mirrored along x, voxel 0 (1.5 mm) at x = 18 and voxel 1 (6 mm) at
  // x = 6. Edges at low x come out longer than at high x.
  writeFloatNifti(dir + "/ramp.nii", 2, 1, 1, 12.0f, {1.5f, 6.0f},
                  {-12.0f, 0.0f, 0.0f, 18.0f, 0.0f, 12.0f, 0.0f, 0.0f, 0.0f, 0.0f, 12.0f, 0.0f});
  r = runCommand(voxmorph("mesh " + quote(grid) + " --size-grid " + quote(dir + "/ramp.nii") + " -q --no-distance -o " +
                          quote(dir + "/ramp.mesh") + " --report " + quote(dir + "/ramp.json")));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const auto rampReport = nlohmann::json::parse(slurp(dir + "/ramp.json"));
  EXPECT_TRUE(rampReport["topology"]["preserved"].get<bool>());
  // The sizing grid is one of the run's inputs.
  bool sizeGridRecorded = false;
  for (const auto& input : rampReport["provenance"]["inputs"])
    sizeGridRecorded |= input["role"] == "size_grid" && input["sha256"].get<std::string>().size() == 64;
  EXPECT_TRUE(sizeGridRecorded) << rampReport["provenance"].dump();
  const TetMesh ramp = readTetMesh(dir + "/ramp.mesh");
  double sum[2] = {0.0, 0.0}, count[2] = {0.0, 0.0};
  for (const Tet& t : ramp.tets)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const Eigen::Vector3d a = ramp.positions[std::size_t(t[i])], b = ramp.positions[std::size_t(t[j])];
        const double x = 0.5 * (a.x() + b.x());
        if (x < 6.0 || x > 18.0) {
          sum[x > 18.0] += (a - b).norm();
          count[x > 18.0] += 1.0;
        }
      }
  ASSERT_GT(count[0], 0.0);
  ASSERT_GT(count[1], 0.0);
  EXPECT_GT(sum[0] / count[0], 1.5 * sum[1] / count[1]) << sum[0] / count[0] << " mm at low x, " << sum[1] / count[1];
}

TEST(RemeshCli, BadSizingIsRefused) {
  const std::string dir = test::tempDir();
  const std::string grid = dir + "/spheres.nii.gz";
  ASSERT_EQ(runCommand(voxmorph("synth spheres --size 12 -o " + quote(grid))).exitCode, 0);
  const std::string out = dir + "/out.mesh";
  const std::string mesh = voxmorph("mesh " + quote(grid) + " -q -o " + quote(out) + " ");
  // Usage errors: exit 2 (the option parser's, and the checks after it).
  for (const char* options : {"--size-boundary 3 --size-interior 2", "--size-boundary 0 --size-interior 2",
                              "--size-boundary -1 --size-interior 2", "--size-boundary 2", "--size-interior 2",
                              "-l 2 --size-boundary 2 --size-interior 4", "", "-l 2 --size-grid x.nii"}) {
    const auto r = runCommand(mesh + options);
    EXPECT_EQ(r.exitCode, 2) << options << ": " << r.err;
  }
  auto r = runCommand(mesh + "--size-boundary 3 --size-interior 2");
  EXPECT_EQ(r.err, "voxmorph: error: --size-interior: l_I = 2 mm is shorter than --size-boundary l_B = 3 mm\n");
  r = runCommand(mesh);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("--length: a target edge length is required"), std::string::npos) << r.err;
  // A size grid with a non-positive value: the file's fault, exit 1.
  std::vector<float> sizes(27, 2.0f);
  sizes[13] = -0.5f;
  writeFloatNifti(dir + "/bad.nii", 3, 3, 3, 10.0f, sizes);
  r = runCommand(mesh + "--size-grid " + quote(dir + "/bad.nii"));
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("bad.nii: voxel 13 (1, 1, 1) holds -0.5: sizes must be finite and positive (mm)"), std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  // A size grid cut short: its header promises more samples than it holds.
  writeFloatNifti(dir + "/short.nii", 3, 3, 3, 10.0f, std::vector<float>(27, 2.0f));
  fs::resize_file(dir + "/short.nii", fs::file_size(dir + "/short.nii") - 40);
  r = runCommand(mesh + "--size-grid " + quote(dir + "/short.nii"));
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(r.err.rfind("voxmorph: error: " + dir + "/short.nii: ", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  // Not a NIfTI file.
  { std::ofstream(dir + "/junk.nii") << "not a grid"; }
  r = runCommand(mesh + "--size-grid " + quote(dir + "/junk.nii"));
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("junk.nii"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// A mesh written with the other orientation convention (every tet negative)
// remeshes like the original: same topology, positive volumes in the report.
TEST(RemeshCli, AcceptsEitherOrientation) {
  const std::string dir = test::tempDir();
  const std::string grid = dir + "/spheres.nii.gz";
  ASSERT_EQ(runCommand(voxmorph("synth spheres --size 12 -o " + quote(grid))).exitCode, 0);
  ASSERT_EQ(runCommand(voxmorph("mesh " + quote(grid) + " -l 2 -q -o " + quote(dir + "/in.mesh"))).exitCode, 0);
  TetMesh mesh = readTetMesh(dir + "/in.mesh");
  for (Tet& t : mesh.tets) std::swap(t[0], t[1]);
  writeTetMesh(dir + "/mirrored.mesh", mesh);
  const auto r = runCommand(voxmorph("remesh " + quote(dir + "/mirrored.mesh") + " -l 3 --iterations 2 --no-distance -o " +
                                     quote(dir + "/out.vtu") + " --report " + quote(dir + "/r.json")));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.err.find("negatively oriented; turned over"), std::string::npos) << r.err;
  const auto report = nlohmann::json::parse(slurp(dir + "/r.json"));
  EXPECT_TRUE(report["topology"]["preserved"].get<bool>());
  EXPECT_EQ(report["inverted_tets"].get<int>(), 0);
  for (const auto& l : report["labels"]) EXPECT_GT(l["volume_mm3"]["input"].get<double>(), 0.0);
}

// Features (thesis 2.3.8): a notched cube's creases and a polyline on its
// top face, kept within 0.1 l and written as Medit Edges and Gmsh physical
// lines that read back the same (and that meshio reads); bad polyline files
// are refused in one line naming the file, nothing written.
TEST(RemeshCli, KeepsSharpFeaturesAndPolylinesAndWritesThem) {
  const std::string dir = test::tempDir();
  GridGeometry g;
  g.dims = {20, 20, 20};
  LabelGrid grid(g, 0);
  for (int z = 3; z < 17; ++z)
    for (int y = 3; y < 17; ++y)
      for (int x = 3; x < 17; ++x)
        if (!(x >= 8 && x < 12 && z >= 12)) grid.at(x, y, z) = 1;
  const TetMesh all = tetrahedralizeVoxels(grid);
  TetMesh cube;
  cube.positions = all.positions;
  for (std::size_t t = 0; t < all.tetCount(); ++t)
    if (all.labels[t] != 0) {
      cube.tets.push_back(all.tets[t]);
      cube.labels.push_back(all.labels[t]);
    }
  writeMedit(dir + "/cube.mesh", cube);
  {
    std::ofstream lines(dir + "/lines.txt");
    lines << "# an L on the top face, left of the notch\n4.5 4.5 16.5 6.5 4.5 16.5\n6.5 4.5 16.5 6.5 14.5 16.5\n";
  }
  const std::string args = " -l 3 -q --iterations 4 --sharp-features --features " + quote(dir + "/lines.txt");
  auto r = runCommand(voxmorph("remesh " + quote(dir + "/cube.mesh") + args + " -o " + quote(dir + "/out.mesh") +
                               " --report " + quote(dir + "/r.json")));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const nlohmann::json report = nlohmann::json::parse(slurp(dir + "/r.json"));
  ASSERT_TRUE(report.contains("features")) << report.dump();
  EXPECT_LT(report["features"]["hausdorff_over_l"]["input_to_output"].get<double>(), 0.1);
  EXPECT_LT(report["features"]["hausdorff_over_l"]["output_to_input"].get<double>(), 0.1);
  EXPECT_GT(report["features"]["lines"].get<int>(), 20);  // the notched cube's 24 creases and the polyline
  const TetMesh out = readTetMesh(dir + "/out.mesh");
  const MeshEdges edges = readMeshEdges(dir + "/out.mesh");
  ASSERT_FALSE(edges.empty());
  EXPECT_EQ(edges.edges.size(), report["features"]["edges_out"].get<std::size_t>());
  std::set<std::pair<std::int32_t, std::int32_t>> meshEdges;
  for (const Tet& t : out.tets)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) meshEdges.insert(std::minmax(t[std::size_t(i)], t[std::size_t(j)]));
  for (const auto& [a, b] : edges.edges) EXPECT_TRUE(meshEdges.count(std::minmax(a, b))) << a << "-" << b;
  const std::set<std::int32_t> refs(edges.refs.begin(), edges.refs.end());
  EXPECT_EQ(*refs.begin(), 1);
  EXPECT_EQ(std::size_t(*refs.rbegin()), refs.size());

  // The same run to Gmsh: the same mesh and lines (vertex order kept).
  r = runCommand(voxmorph("remesh " + quote(dir + "/cube.mesh") + args + " -o " + quote(dir + "/out.msh")));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(readTetMesh(dir + "/out.msh").positions, out.positions);
  const MeshEdges lines = readMeshEdges(dir + "/out.msh");
  auto sorted = [](const MeshEdges& m) {
    std::vector<std::tuple<std::int32_t, std::int32_t, std::int32_t>> v;
    for (std::size_t i = 0; i < m.edges.size(); ++i) v.emplace_back(m.refs[i], m.edges[i][0], m.edges[i][1]);
    std::sort(v.begin(), v.end());
    return v;
  };
  EXPECT_EQ(sorted(lines), sorted(edges));
  if (!test::python().empty()) {
    r = runCommand(quote(test::python()) + " -c " +
                   quote("import meshio; m = meshio.read('" + dir + "/out.msh'); "
                         "n = sum(len(c.data) for c in m.cells if c.type == 'line'); "
                         "p = sorted({int(x) for c, d in zip(m.cells, m.cell_data['gmsh:physical']) if c.type == 'line' for x in d}); "
                         "print(n, len(p), p[0], p[-1])"));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::string expected = std::to_string(edges.edges.size()) + " " + std::to_string(refs.size()) + " 1 " +
                                 std::to_string(refs.size()) + "\n";
    EXPECT_NE(r.out.find(expected), std::string::npos) << r.out;
  }

  // Bad polyline files: exit 1, one line naming the file and the fault.
  struct Bad {
    const char* text;
    const char* fault;
  };
  for (const Bad& bad : {Bad{"4.5 4.5 16.5 6.5 4.5\n", "line 1: 5 numbers"},
                         Bad{"# nothing\n", "no segments"},
                         Bad{"4.5 4.5 16.5 6.5 4.5 x\n", "'x' is not a finite number"},
                         Bad{"4.5 4.5 16.5 6.5 4.5 16.5\n4.5 4.5 16.5 4.5 4.5 90\n", "segment 2: point (4.5, 4.5, 90)"}}) {
    {
      std::ofstream f(dir + "/bad.txt");
      f << bad.text;
    }
    const std::string target = dir + "/bad_out.mesh";
    r = runCommand(voxmorph("remesh " + quote(dir + "/cube.mesh") + " -l 3 -q --features " + quote(dir + "/bad.txt") +
                            " -o " + quote(target)));
    EXPECT_EQ(r.exitCode, 1) << bad.text;
    EXPECT_NE(r.err.find("bad.txt"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(bad.fault), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(target));
  }
  // The same polyline as a Medit file of Vertices and Edges (no tetrahedra).
  {
    std::ofstream f(dir + "/lines.mesh");
    f << "MeshVersionFormatted 2\nDimension 3\nVertices\n3\n4.5 4.5 16.5 0\n6.5 4.5 16.5 0\n6.5 14.5 16.5 0\n"
         "Edges\n2\n1 2 7\n2 3 7\nEnd\n";
  }
  r = runCommand(voxmorph("remesh " + quote(dir + "/cube.mesh") + " -l 3 -q --iterations 4 --features " +
                          quote(dir + "/lines.mesh") + " -o " + quote(dir + "/medit.mesh") + " --report -"));
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const nlohmann::json fromMedit = nlohmann::json::parse(r.out);
  EXPECT_EQ(fromMedit["features"]["lines"].get<int>(), 1);
  EXPECT_LT(fromMedit["features"]["hausdorff_over_l"]["input_to_output"].get<double>(), 0.1);
  {
    std::ofstream f(dir + "/bad.mesh");
    f << "MeshVersionFormatted 2\nDimension 3\nVertices\n2\n4.5 4.5 16.5 0\n6.5 4.5 16.5 0\nEdges\n1\n1 3 7\nEnd\n";
  }
  r = runCommand(voxmorph("remesh " + quote(dir + "/cube.mesh") + " -l 3 -q --features " + quote(dir + "/bad.mesh") +
                          " -o " + quote(dir + "/bad_out.mesh")));
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("bad.mesh"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("edge 1 references vertex 3"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir + "/bad_out.mesh"));

  // Lines have no place in a .vtu: a usage error.
  r = runCommand(voxmorph("remesh " + quote(dir + "/cube.mesh") + " -l 3 -q --sharp-features -o " + quote(dir + "/o.vtu")));
  EXPECT_EQ(r.exitCode, 2) << r.err;
  EXPECT_FALSE(fs::exists(dir + "/o.vtu"));
}

}  // namespace
}  // namespace vox::remesh
