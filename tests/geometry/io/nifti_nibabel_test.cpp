// NIfTI against a real client: Debian's python3-nibabel reads what we write
// (shape, dtype, affine, a checksum of the data) and writes files we read
// exactly (uint8, int16, float32 holding integers, scaled int16, qform-only
// with a mirrored affine; plain and gzip).

#include "geometry/io/grid_io.h"
#include "tests/geometry/io/grid_test_grids.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <map>
#include <sstream>

namespace vox {
namespace {

test::CommandResult runPython(const std::string& dir, const std::string& script, const std::string& args) {
  const std::string scriptPath = dir + "/script.py";
  test::writeBytes(scriptPath, script);
  return test::runCommand(test::quote(test::python()) + " " + test::quote(scriptPath) + " " + args);
}

// Prints, for each file: dtype, shape, the 16 affine entries, the checksum
// of labelChecksum() and the transform codes, as nibabel sees them.
const char* const kDescribe = R"PY(
import sys
import nibabel as nib
import numpy as np
for path in sys.argv[1:]:
    img = nib.load(path)
    data = np.asanyarray(img.dataobj)
    flat = data.ravel(order="F").astype(np.uint64)
    weights = np.arange(flat.size, dtype=np.uint64) % 65521 + 1
    hdr = img.header
    print(data.dtype, *data.shape, *img.affine.ravel().tolist(), int(np.sum(flat * weights)),
          int(hdr["qform_code"]), int(hdr["sform_code"]), int(hdr["xyzt_units"]))
)PY";

TEST(NiftiNibabel, ReadsOurFiles) {
  if (test::python().empty()) GTEST_SKIP() << "python3 with nibabel is not installed";
  const std::string dir = test::tempDir();
  std::vector<std::pair<std::string, LabelGrid>> files;
  for (const char* ext : {".nii", ".nii.gz"})
    for (Label maxLabel : {Label(250), Label(60000)})
      for (bool mirrored : {false, true}) {
        const std::string path = dir + "/ours" + std::to_string(maxLabel) + (mirrored ? "m" : "r") + ext;
        files.emplace_back(path, test::makeTestGrid(maxLabel, mirrored));
        writeGrid(path, files.back().second);
      }
  std::string args;
  for (const auto& f : files) args += " " + test::quote(f.first);
  const test::CommandResult r = runPython(dir, kDescribe, args);
  ASSERT_EQ(r.exitCode, 0) << r.err;

  std::istringstream lines(r.out);
  for (const auto& [path, grid] : files) {
    SCOPED_TRACE(path);
    std::string dtype;
    Index3 shape;
    Eigen::Matrix4d affine;
    std::uint64_t checksum = 0;
    int qformCode = 0, sformCode = 0, units = 0;
    lines >> dtype >> shape[0] >> shape[1] >> shape[2];
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) lines >> affine(r, c);
    lines >> checksum >> qformCode >> sformCode >> units;
    ASSERT_TRUE(lines) << r.out;
    EXPECT_EQ(dtype, grid.maxLabel() <= 255 ? "uint8" : "uint16");
    EXPECT_EQ(shape, grid.dims());
    EXPECT_LT((affine - grid.geometry().indexToWorld()).cwiseAbs().maxCoeff(), 1e-4) << affine;
    EXPECT_EQ(checksum, test::labelChecksum(grid));
    EXPECT_EQ(qformCode, 1);
    EXPECT_EQ(sformCode, 1);
    EXPECT_EQ(units, 2);  // NIFTI_UNITS_MM
  }
}

// Writes the files and prints "name affine(16)" for each, as nibabel saw it.
const char* const kWrite = R"PY(
import sys
import nibabel as nib
import numpy as np
out = sys.argv[1]
i, j, k = np.meshgrid(np.arange(19), np.arange(14), np.arange(9), indexing="ij")
pattern = 3 * i + 5 * j + 7 * k + i * j * k
angle, axis = 0.6, np.array([2.0, -1.0, 0.5])
axis /= np.linalg.norm(axis)
K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
R = np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K
affine = np.eye(4)
affine[:3, :3] = R @ np.diag([0.9, 1.1, 2.3])
affine[:3, 3] = [-50.5, 20.25, 10.0]
mirrored = affine.copy()
mirrored[:3, 0] *= -1

def save(name, data, aff=affine, qform_only=False):
    img = nib.Nifti1Image(data, aff)
    if qform_only:
        img.set_sform(None, code=0)
        img.set_qform(aff, code=1)
    nib.save(img, out + "/" + name)
    back = nib.load(out + "/" + name)
    print(name, *back.affine.ravel().tolist())

save("u8.nii", (pattern % 251).astype(np.uint8))
save("u8.nii.gz", (pattern % 251).astype(np.uint8))
save("i16.nii", (pattern % 30011).astype(np.int16))
save("i16.nii.gz", (pattern % 30011).astype(np.int16))
save("f32.nii", (pattern % 65536).astype(np.float32))
save("f32.nii.gz", (pattern % 65536).astype(np.float32))
save("qform.nii.gz", (pattern % 251).astype(np.uint8), mirrored, qform_only=True)
# Stored int16 with scl_slope 2, scl_inter 1: labels are 2 * stored + 1.
save("scaled.nii", (pattern % 20000).astype(np.int16))
with open(out + "/scaled.nii", "r+b") as f:
    f.seek(112)
    f.write(np.array([2.0, 1.0], dtype="<f4").tobytes())
print("scaled_max", int(np.asarray(nib.load(out + "/scaled.nii").dataobj).max()))
)PY";

TEST(NiftiNibabel, WeReadItsFilesExactly) {
  if (test::python().empty()) GTEST_SKIP() << "python3 with nibabel is not installed";
  const std::string dir = test::tempDir();
  const test::CommandResult r = runPython(dir, kWrite, test::quote(dir));
  ASSERT_EQ(r.exitCode, 0) << r.err;

  const std::map<std::string, std::int64_t> modulus = {{"u8.nii", 251},   {"u8.nii.gz", 251},  {"i16.nii", 30011},
                                                       {"i16.nii.gz", 30011}, {"f32.nii", 65536}, {"f32.nii.gz", 65536},
                                                       {"qform.nii.gz", 251}, {"scaled.nii", 20000}};
  std::istringstream lines(r.out);
  std::string name;
  int seen = 0;
  while (lines >> name) {
    if (name == "scaled_max") {
      std::int64_t maxValue = 0;
      lines >> maxValue;
      EXPECT_GT(maxValue, 255);  // the scaled file really needs uint16 labels
      continue;
    }
    SCOPED_TRACE(name);
    Eigen::Matrix4d affine;
    for (int row = 0; row < 4; ++row)
      for (int c = 0; c < 4; ++c) lines >> affine(row, c);
    ASSERT_TRUE(modulus.count(name));
    ++seen;
    const LabelGrid grid = readGrid(dir + "/" + name);
    ASSERT_EQ(grid.dims(), (Index3{19, 14, 9}));
    EXPECT_LT((grid.geometry().indexToWorld() - affine).cwiseAbs().maxCoeff(), 1e-4) << grid.geometry().indexToWorld();
    const bool scaled = name == "scaled.nii";
    for (std::int64_t k = 0; k < 9; ++k)
      for (std::int64_t j = 0; j < 14; ++j)
        for (std::int64_t i = 0; i < 19; ++i) {
          const Label stored = test::patternLabel(i, j, k, modulus.at(name));
          ASSERT_EQ(grid.at(i, j, k), scaled ? Label(2 * stored + 1) : stored) << i << " " << j << " " << k;
        }
  }
  EXPECT_EQ(seen, 8);
}

}  // namespace
}  // namespace vox
