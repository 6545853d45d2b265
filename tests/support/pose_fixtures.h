#pragma once
// The pose files of assets/poses applied to their ICRP phantom ("am_*" to the
// adult male, "af_*" to the adult female) as `voxmorph deform` applies them
// (same cage, separations, cuts and handles; no envelope, which only the
// display needs, and no refinement; joint poses compiled against the
// phantom's skeleton), with the CPU reference rasterization of the posed
// grid. Computed once per process and pose.

#include "geometry/deform/pipeline.h"
#include "geometry/raster/rasterize.h"
#include "geometry/io/grid_io.h"
#include "geometry/organ_table.h"
#include "geometry/deform/pose/joint_pose.h"
#include "tests/support/test_environment.h"

#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace vox::test {

struct PosedPhantom {
  std::string pose;      // file name, e.g. "am_right_arm_raised_45.json"
  std::string phantom;   // "icrp110_am" or "icrp110_af"
  LabelGrid source;
  OrganTable organs;
  TetMesh rest;          // transfer mesh at rest (cut where the pose separates limbs)
  std::vector<Eigen::Vector3d> deformed;
  std::vector<std::uint8_t> inside;  // per TM vertex: 1 inside the cage, 0 placed by the propagation
  std::size_t outsideVertices = 0;
  LabelGrid cpu;         // CPU reference rasterization of the posed grid
};

// Pose files in assets/poses, sorted by name: those the cage pipeline poses
// (poseFiles), those marked "articulated" (the transfer mesh that resolves
// the skeleton poses them: articulatedPoseFiles).
inline std::vector<std::string> assetPoseFiles(bool articulated) {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(assetPath("poses")))
    if (e.path().extension() == ".json" && readPose(e.path().string()).articulated == articulated)
      names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}
inline std::vector<std::string> poseFiles() { return assetPoseFiles(false); }
inline std::vector<std::string> articulatedPoseFiles() { return assetPoseFiles(true); }

inline std::string phantomOfPose(const std::string& pose) {
  return pose.rfind("af_", 0) == 0 ? "icrp110_af" : "icrp110_am";
}

inline const PosedPhantom& posedPhantom(const std::string& pose) {
  static std::map<std::string, std::unique_ptr<PosedPhantom>> cache;
  std::unique_ptr<PosedPhantom>& slot = cache[pose];
  if (slot) return *slot;
  auto p = std::make_unique<PosedPhantom>();
  p->pose = pose;
  p->phantom = phantomOfPose(pose);
  p->source = readGrid(assetPath(p->phantom + ".nii.gz"));
  p->organs = OrganTable::read(assetPath(p->phantom + "_organs.dat"));
  const std::string path = assetPath("poses/" + pose);
  PipelineOptions options = skeleton::skeletalPoseOptions(readPose(path), path, p->source, p->organs, {}, std::nullopt);
  options.envelope = false;
  DeformationPipeline pipeline(p->source, options);
  pipeline.deform();
  p->rest = pipeline.transferMesh();
  p->deformed = pipeline.deformedTransferMesh();
  p->inside = pipeline.transferMeshInside();
  p->outsideVertices = std::size_t(std::count(p->inside.begin(), p->inside.end(), std::uint8_t(0)));
  p->cpu = rasterizeDeformedGrid(p->source, p->rest, p->deformed);
  slot = std::move(p);
  return *slot;
}

}  // namespace vox::test
