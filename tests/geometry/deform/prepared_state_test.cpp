// The saved rest state (prepared_state.h, prepare_run.h) on the synthetic
// skeleton figure: it reads back bit for bit; a pipeline that takes it builds
// the same transfer mesh, cage and posed positions as one that builds them;
// one that asks for separations, cage options or label groups it lacks is
// refused naming what differs; inputs that differ (grid, organ table) are
// refused; a truncated, corrupted, foreign or other-version file, and one
// whose counts exceed its bytes, are one-line InputErrors, nothing allocated
// from them.

#include "geometry/deform/pipeline.h"
#include "geometry/deform/pose/joint_pose.h"
#include "geometry/deform/pose/pose_editor.h"
#include "geometry/deform/prepared_state.h"
#include "geometry/deform/run/deform_run.h"
#include "geometry/deform/run/prepare_run.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/section_file.h"
#include "geometry/parallel.h"
#include "geometry/skeleton/label_groups.h"
#include "geometry/synth.h"
#include "tests/support/test_environment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <zlib.h>
#include <memory>

namespace vox {
namespace {

struct Figure {
  std::string dir, grid;
  LabelGrid labels;
  OrganTable organs;
};

const Figure& figure() {
  static const Figure f = [] {
    Figure out;
    out.dir = test::tempDir();
    out.grid = out.dir + "/figure.mha";
    out.labels = synthesize(SynthKind::SkeletonFigure, 64);
    out.organs = synthOrganTable(SynthKind::SkeletonFigure);
    writeGrid(out.grid, out.labels);
    return out;
  }();
  return f;
}

Pose jointPose(const std::string& joint, const std::string& dof, double degrees) {
  Pose pose;
  PoseJoint j;
  j.name = joint;
  j.degrees[dof == "flexion" ? 0 : dof == "abduction" ? 1 : 2] = degrees;
  pose.joints.push_back(j);
  return pose;
}

// The figure prepared for a right-shoulder pose and for a pose without
// separations.
PrepareRequest prepareRequest() {
  PrepareRequest request;
  request.input = figure().grid;
  request.organs = figure().organs;
  request.organsSource = "figure.dat";
  request.poses = {jointPose("right_shoulder", "abduction", 30), Pose{}};
  request.poseSources = {"shoulder", "still"};
  return request;
}

const PrepareResult& prepared() {
  static const PrepareResult r = prepareRestState(prepareRequest());
  return r;
}

DeformGridRequest runRequest(const Pose& pose) {
  DeformGridRequest r;
  r.input = figure().grid;
  r.pose = pose;
  r.poseSource = "pose";
  r.organs = figure().organs;
  r.organsSource = "figure.dat";
  return r;
}

bool samePoints(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Eigen::Vector3d)) == 0);
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(PreparedState, HoldsTheSkeletonAndOneCageAndMeshPerSetOfSeparations) {
  const PreparedState& s = prepared().state;
  ASSERT_TRUE(s.skeleton.has_value());
  EXPECT_EQ(s.skeleton->joints.size(), 14u);
  EXPECT_EQ(s.cages.size(), 2u);
  EXPECT_EQ(s.meshes.size(), 2u);
  EXPECT_GE(s.envelopes.size(), 1u);
  EXPECT_NE(s.cages[0].separations.find("right_arm:trunk"), std::string::npos) << s.cages[0].separations;
  EXPECT_EQ(s.cages[1].separations, "none");
  EXPECT_EQ(s.inputs.workingFactor, 1);
  EXPECT_FALSE(s.recording);
}

// The cage and the transfer mesh are built at once (pipeline.h): the file
// holds the same bytes whichever finishes first, on one thread or several.
TEST(PreparedState, TheSameBytesOnOneAndTwoThreadsAndRunAfterRun) {
  const auto bytesOn = [](int threads) {
    const ScopedWorkerThreads scope(threads);
    PreparedState state = prepareRestState(prepareRequest()).state;
    state.skeleton->seconds = 0.0;  // the time it took, the one field that differs
    return state.bytes();
  };
  const std::string one = bytesOn(1);
  EXPECT_TRUE(one == bytesOn(2));
  EXPECT_TRUE(one == bytesOn(2));
  EXPECT_TRUE(one == bytesOn(1));
}

// A first pose that does not compile against the skeleton: the first
// pipeline builds the skeleton while it builds its transfer mesh; the state
// holds what it holds when the skeleton is built first.
TEST(PreparedState, TheSkeletonBuiltBesideTheFirstTransferMeshIsTheSame) {
  PrepareRequest request = prepareRequest();
  request.poses = {Pose{}, jointPose("right_shoulder", "abduction", 30)};
  request.poseSources = {"still", "shoulder"};
  const PrepareResult r = prepareRestState(request);
  const PreparedState& s = prepared().state;
  ASSERT_TRUE(r.state.skeleton.has_value());
  EXPECT_EQ(r.state.skeleton->parts.parts.labels(), s.skeleton->parts.parts.labels());
  EXPECT_EQ(r.state.skeleton->joints.size(), s.skeleton->joints.size());
  ASSERT_EQ(r.state.cages.size(), 2u);
  ASSERT_EQ(r.state.meshes.size(), 2u);
  for (const auto& [mine, theirs] : {std::pair{0, 1}, std::pair{1, 0}}) {
    EXPECT_EQ(r.state.cages[mine].key, s.cages[theirs].key);
    EXPECT_TRUE(samePoints(r.state.cages[mine].cage.positions, s.cages[theirs].cage.positions));
    EXPECT_EQ(r.state.meshes[mine].key, s.meshes[theirs].key);
    EXPECT_TRUE(samePoints(r.state.meshes[mine].mesh.positions, s.meshes[theirs].mesh.positions));
    EXPECT_EQ(r.state.meshes[mine].mesh.tets, s.meshes[theirs].mesh.tets);
  }
  const auto skeletonStage = std::find_if(r.stages.begin(), r.stages.end(), [](const StageTime& t) { return t.name == "still: skeleton"; });
  EXPECT_NE(skeletonStage, r.stages.end());
}

// Without a prepared state, deform's body parts (a pose without joints) are
// computed while the pipeline builds the transfer mesh: the same parts, the
// same cage vertices' parts, the same transfer mesh as the stored ones.
TEST(PreparedState, BodyPartsComputedBesideTheTransferMeshAreTheStoredOnes) {
  const LabelGrid& grid = figure().labels;
  auto state = std::make_shared<PreparedState>(PreparedState::fromBytes(prepared().state.bytes(), "figure.vxprep"));
  const DeformGridRequest request = runRequest(Pose{});
  PipelineOptions meanwhile = deformPipelineOptions(request, grid, 1);
  PipelineOptions taken = deformPipelineOptions(request, grid, 1, state.get());
  ASSERT_TRUE(bool(meanwhile.bodyPartsMeanwhile));
  EXPECT_FALSE(meanwhile.bodyParts.has_value());
  EXPECT_FALSE(bool(taken.bodyPartsMeanwhile));
  meanwhile.pose.reset();
  taken.pose.reset();
  taken.prepared = state;
  const DeformationPipeline a(grid, meanwhile), b(grid, taken);
  ASSERT_TRUE(a.bodyParts().has_value());
  ASSERT_TRUE(b.bodyParts().has_value());
  EXPECT_EQ(a.bodyParts()->labels(), b.bodyParts()->labels());
  EXPECT_EQ(a.cageBodyParts(), b.cageBodyParts());
  EXPECT_TRUE(samePoints(a.transferMesh().positions, b.transferMesh().positions));
  EXPECT_EQ(a.transferMesh().tets, b.transferMesh().tets);
  EXPECT_EQ(a.rigidBones().vertexGroup, b.rigidBones().vertexGroup);
  const std::vector<StageTime>& stages = a.stats().stages;
  EXPECT_TRUE(std::any_of(stages.begin(), stages.end(), [](const StageTime& t) { return t.name == "skeleton"; }));
}

TEST(PreparedState, ReadsBackBitForBit) {
  const PreparedState& s = prepared().state;
  const std::string path = figure().dir + "/figure.vxprep";
  s.write(path);
  const PreparedState r = PreparedState::read(path);
  EXPECT_EQ(r.source, path);
  ASSERT_EQ(r.inputs.files.size(), s.inputs.files.size());
  for (std::size_t i = 0; i < s.inputs.files.size(); ++i) {
    EXPECT_EQ(r.inputs.files[i].role, s.inputs.files[i].role);
    EXPECT_EQ(r.inputs.files[i].sha256, s.inputs.files[i].sha256);
  }
  EXPECT_EQ(r.inputs.workingDims, s.inputs.workingDims);
  EXPECT_EQ(r.inputs.build, s.inputs.build);
  ASSERT_TRUE(r.skeleton.has_value());
  EXPECT_EQ(r.skeleton->parts.parts.labels(), s.skeleton->parts.parts.labels());
  EXPECT_EQ(r.skeleton->parts.parts.geometry().origin, s.skeleton->parts.parts.geometry().origin);
  EXPECT_EQ(r.skeleton->parts.voxels, s.skeleton->parts.voxels);
  EXPECT_EQ(r.skeleton->parts.seedBones, s.skeleton->parts.seedBones);
  ASSERT_EQ(r.skeleton->parts.bones.size(), s.skeleton->parts.bones.size());
  for (std::size_t i = 0; i < s.skeleton->parts.bones.size(); ++i) EXPECT_EQ(r.skeleton->parts.bones[i].voxels, s.skeleton->parts.bones[i].voxels);
  ASSERT_EQ(r.skeleton->joints.size(), s.skeleton->joints.size());
  for (std::size_t i = 0; i < s.skeleton->joints.size(); ++i) {
    EXPECT_EQ(r.skeleton->joints[i].id, s.skeleton->joints[i].id);
    EXPECT_EQ(r.skeleton->joints[i].centre, s.skeleton->joints[i].centre);
    EXPECT_EQ(r.skeleton->joints[i].leftRight, s.skeleton->joints[i].leftRight);
    EXPECT_EQ(r.skeleton->joints[i].method, s.skeleton->joints[i].method);
  }
  ASSERT_EQ(r.cages.size(), s.cages.size());
  for (std::size_t i = 0; i < s.cages.size(); ++i) {
    EXPECT_EQ(r.cages[i].key, s.cages[i].key);
    EXPECT_TRUE(samePoints(r.cages[i].cage.positions, s.cages[i].cage.positions));
    EXPECT_EQ(r.cages[i].cage.triangles, s.cages[i].cage.triangles);
    EXPECT_EQ(r.cages[i].report.check.volume, s.cages[i].report.check.volume);
    EXPECT_EQ(r.cages[i].report.foregroundOutside, s.cages[i].report.foregroundOutside);
  }
  ASSERT_EQ(r.meshes.size(), s.meshes.size());
  for (std::size_t i = 0; i < s.meshes.size(); ++i) {
    EXPECT_EQ(r.meshes[i].key, s.meshes[i].key);
    EXPECT_TRUE(samePoints(r.meshes[i].mesh.positions, s.meshes[i].mesh.positions));
    EXPECT_EQ(r.meshes[i].mesh.tets, s.meshes[i].mesh.tets);
    EXPECT_EQ(r.meshes[i].mesh.labels, s.meshes[i].mesh.labels);
    ASSERT_EQ(r.meshes[i].cutReports.size(), s.meshes[i].cutReports.size());
    for (std::size_t c = 0; c < s.meshes[i].cutReports.size(); ++c)
      EXPECT_EQ(r.meshes[i].cutReports[c].splitVertices, s.meshes[i].cutReports[c].splitVertices);
    EXPECT_EQ(r.meshes[i].uncoveredVoxels, s.meshes[i].uncoveredVoxels);
  }
  ASSERT_EQ(r.envelopes.size(), s.envelopes.size());
  for (std::size_t i = 0; i < s.envelopes.size(); ++i) EXPECT_TRUE(samePoints(r.envelopes[i].envelope.positions, s.envelopes[i].envelope.positions));
  // Written again, the same bytes.
  EXPECT_EQ(r.bytes(), s.bytes());
}

TEST(PreparedState, APipelineThatTakesItPosesExactlyAsOneThatBuildsIt) {
  const LabelGrid& grid = figure().labels;
  const Pose pose = jointPose("right_shoulder", "abduction", 30);
  auto state = std::make_shared<PreparedState>(PreparedState::fromBytes(prepared().state.bytes(), "figure.vxprep"));
  EXPECT_EQ(state->check(preparedInputs(figure().grid, figure().organs, "figure.dat", "", 1, grid.dims())), "");

  const DeformGridRequest request = runRequest(pose);
  PipelineOptions built = deformPipelineOptions(request, grid, 1);
  PipelineOptions taken = deformPipelineOptions(request, grid, 1, state.get());
  taken.prepared = state;
  DeformationPipeline a(grid, built), b(grid, taken);
  a.deform();
  b.deform();
  EXPECT_TRUE(samePoints(a.builtCage().positions, b.builtCage().positions));
  EXPECT_TRUE(samePoints(a.envelope().positions, b.envelope().positions));
  EXPECT_TRUE(samePoints(a.transferMesh().positions, b.transferMesh().positions));
  EXPECT_EQ(a.transferMesh().tets, b.transferMesh().tets);
  EXPECT_EQ(a.stats().uncoveredVoxels, b.stats().uncoveredVoxels);
  EXPECT_EQ(a.stats().cage.meshedVertices, b.stats().cage.meshedVertices);
  EXPECT_TRUE(samePoints(a.deformedTransferMesh(), b.deformedTransferMesh()));
}

TEST(PreparedState, TheViewersSessionStartsFromIt) {
  // The PoseEditor (the viewer's session) on a joint pose and on a pose
  // without separations: the same cage, envelope and transfer mesh as built.
  auto state = std::make_shared<PreparedState>(PreparedState::fromBytes(prepared().state.bytes(), "figure.vxprep"));
  for (const Pose& setup : {jointPose("right_shoulder", "abduction", 45), Pose{}}) {
    const PoseEditor built(figure().labels, figure().organs, setup, "setup");
    const PoseEditor taken(figure().labels, figure().organs, setup, "setup", {}, state);
    EXPECT_TRUE(samePoints(built.pipeline().builtCage().positions, taken.pipeline().builtCage().positions));
    EXPECT_TRUE(samePoints(built.pipeline().envelope().positions, taken.pipeline().envelope().positions));
    EXPECT_TRUE(samePoints(built.pipeline().transferMesh().positions, taken.pipeline().transferMesh().positions));
    EXPECT_EQ(built.pipeline().transferMesh().tets, taken.pipeline().transferMesh().tets);
    EXPECT_EQ(built.turnsJoints(), taken.turnsJoints());
  }
}

TEST(PreparedState, RefusesWhatItWasNotPreparedFor) {
  const LabelGrid& grid = figure().labels;
  auto state = std::make_shared<PreparedState>(PreparedState::fromBytes(prepared().state.bytes(), "figure.vxprep"));
  const auto run = [&](const DeformGridRequest& request) {
    PipelineOptions options = deformPipelineOptions(request, grid, 1, state.get());
    options.prepared = state;
    DeformationPipeline pipeline(grid, options);
  };
  // Another limb's separations.
  std::string e = errorOf([&] { run(runRequest(jointPose("left_knee", "flexion", 30))); });
  EXPECT_NE(e.find("figure.vxprep: prepared for other separations"), std::string::npos) << e;
  EXPECT_NE(e.find("left_leg:right_leg"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos);
  // Other cage options.
  DeformGridRequest dilated = runRequest(Pose{});
  dilated.dilationMm = 25;
  e = errorOf([&] { run(dilated); });
  EXPECT_NE(e.find("prepared with other cage options"), std::string::npos) << e;
  EXPECT_NE(e.find("--dilation 25 mm"), std::string::npos) << e;
  // The same pose still finds its own.
  EXPECT_EQ(errorOf([&] { run(runRequest(jointPose("right_shoulder", "abduction", 60))); }), "");
  // Its transfer mesh built with other options (another version's): named.
  e = errorOf([&] {
    PipelineOptions options = deformPipelineOptions(runRequest(jointPose("right_shoulder", "abduction", 60)), grid, 1, state.get());
    options.prepared = state;
    options.transferMesh.coverageCaps = false;
    DeformationPipeline pipeline(grid, options);
  });
  EXPECT_NE(e.find("figure.vxprep: holds this run's transfer mesh built with other options"), std::string::npos) << e;
  EXPECT_NE(e.find(" caps), not this run's"), std::string::npos) << e;
  EXPECT_NE(e.find("voxmorph prepare makes it again"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos);

  // Inputs: another organ table, another grid, none.
  OrganTable other = figure().organs;
  Organ extra;
  extra.id = 999;
  extra.name = "extra";
  other.add(extra);
  e = errorOf([&] { state->check(preparedInputs(figure().grid, other, "other.dat", "", 1, grid.dims())); });
  EXPECT_NE(e.find("prepared from another organ table (figure.dat"), std::string::npos) << e;
  e = errorOf([&] { state->check(preparedInputs(figure().grid, std::nullopt, "", "", 1, grid.dims())); });
  EXPECT_NE(e.find("this run has none"), std::string::npos) << e;
  const std::string moved = figure().dir + "/other.mha";
  LabelGrid changed = grid;
  changed.labels()[0] = 1;
  writeGrid(moved, changed);
  e = errorOf([&] { state->check(preparedInputs(moved, figure().organs, "figure.dat", "", 1, grid.dims())); });
  EXPECT_NE(e.find("prepared from another grid"), std::string::npos) << e;
  // A build other than the maker's: a warning, not a refusal.
  PreparedInputs later = preparedInputs(figure().grid, figure().organs, "figure.dat", "", 1, grid.dims());
  later.build += " (later)";
  EXPECT_NE(state->check(later).find("prepared by"), std::string::npos);
}

TEST(PreparedState, RefusesTruncatedCorruptedForeignAndOtherVersionFiles) {
  const std::string bytes = prepared().state.bytes();
  const auto refusal = [](std::string b) { return errorOf([&] { PreparedState::fromBytes(std::move(b), "p.vxprep"); }); };
  // Every prefix: "truncated" (or not a prepared state at all for the
  // shortest), never a crash or an allocation from a length.
  for (std::size_t n = 0; n < bytes.size(); n += std::max<std::size_t>(1, bytes.size() / 997)) {
    const std::string e = refusal(bytes.substr(0, n));
    EXPECT_TRUE(e.find("truncated") != std::string::npos || e.find("not a voxmorph prepared state") != std::string::npos) << n << ": " << e;
    EXPECT_EQ(e.rfind("p.vxprep: ", 0), 0u) << e;
  }
  // A flipped byte anywhere past the version: "corrupted".
  for (std::size_t at = 12; at < bytes.size(); at += std::max<std::size_t>(1, bytes.size() / 499)) {
    std::string b = bytes;
    b[at] = char(b[at] ^ 0x5a);
    const std::string e = refusal(b);
    EXPECT_TRUE(e.find("corrupted") != std::string::npos || e.find("truncated") != std::string::npos) << at << ": " << e;
  }
  std::string b = bytes;
  b[3] = 'X';
  EXPECT_NE(refusal(b).find("not a voxmorph prepared state (voxmorph prepare writes them)"), std::string::npos);
  b = bytes;
  b[8] = char(kPreparedStateVersion + 1);
  EXPECT_NE(refusal(b).find("voxmorph prepared state format version " + std::to_string(kPreparedStateVersion + 1) + ", this voxmorph reads version"),
            std::string::npos)
      << refusal(b);
  EXPECT_NE(refusal(bytes + "x").find("corrupted"), std::string::npos);
  EXPECT_NE(errorOf([] { PreparedState::read(figure().dir + "/missing.vxprep"); }).find("cannot open"), std::string::npos);
}

TEST(PreparedState, ACountBeyondItsBytesIsRefusedBeforeAnythingIsAllocated) {
  // A well-formed file (right magic, version, length, CRC) whose inputs
  // section claims 2^60 digests, then one whose section claims more packed
  // bytes than deflate can make of its compressed ones.
  const SectionFileKind kind{"VXPREP\r\n", kPreparedStateVersion, "voxmorph prepared state", "voxmorph prepare"};
  SectionPacker p;
  p.put(std::uint64_t(1) << 60);
  SectionFileWriter w(kind);
  w.add("inputs", p.bytes());
  std::string e = errorOf([&] { PreparedState::fromBytes(w.bytes(), "p.vxprep"); });
  EXPECT_NE(e.find("p.vxprep: section 'inputs': truncated"), std::string::npos) << e;

  SectionPacker small;
  for (int i = 0; i < 3; ++i) small.put(std::int64_t(1) << 40);
  SectionFileWriter v(kind);
  v.add("inputs", small.bytes());
  std::string bytes = v.bytes();
  // The section's packed size patched to 2^50 and the CRC made to match:
  // refused from deflate's largest ratio, before inflating.
  const std::size_t at = 24 + 2 + 6;  // header, name length, "inputs"
  const std::uint64_t huge = std::uint64_t(1) << 50;
  std::memcpy(bytes.data() + at, &huge, 8);
  const auto crc = std::uint32_t(crc32(0L, reinterpret_cast<const Bytef*>(bytes.data()), uInt(bytes.size() - 4)));
  std::memcpy(bytes.data() + bytes.size() - 4, &crc, 4);
  e = errorOf([&] { PreparedState::fromBytes(bytes, "p.vxprep"); });
  EXPECT_NE(e.find("p.vxprep: corrupted (section 'inputs' declares 1125899906842624 bytes"), std::string::npos) << e;
}

}  // namespace
}  // namespace vox
