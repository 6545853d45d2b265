// The articulated transfer mesh posed by a joint pose (not in ctest): the
// figures of the hard postures in docs/BENCHMARKS.md ("The hard postures on
// the articulated transfer mesh"). What `deform --articulated` runs before
// the rasterization, with what the run's report leaves out: per step the
// smallest det J and the bones' lag, per segment the lag after the
// approach, and the inverted tets by nearest joint.
//
//   build/release/bench/articulated_pose_bench assets/icrp110_am.nii.gz
//       assets/icrp110_am_organs.dat assets/poses/am_phone_call_joints.json [options]
//   build/release/bench/articulated_pose_bench --figure POSE [options]   # the synthetic figure (96)
//
// Options: --steps N (pose steps; default the run's, articulatedPoseSteps),
// --bone-weight W,
// --sliding-weight W (the sliding vertices' pull onto their bodies),
// --max-iterations N (SLIM iterations per step), --volume-weight L (lambda),
// --direct-limit N (unknowns up to which CHOLMOD factorizes every
// iteration), --scapulae (moving
// scapulae), --yielding-shell V (the shoulders' yielding shell, V voxels
// thick; default none), --yielding-hips (the hips' shell too),
// --dump PREFIX (the mesh's arrays for numpy, rest, every step's and posed: dumpMesh),
// --mesh-only (build the mesh, dump it, stop), --squeezed F (per step, the tets under F of their rest volume, by nearest
// joint and by what holds their vertices: where the tissue locks),
// --trunk-reach MM, --pelvis-reach MM (trunk or pelvis bones this near a
// joint centre resolved; default the mesh's), --joint-clearance MM (the head's, hands'
// and feet's tissue this near their joint bends; beyond, rigid whole),
// --still-beyond MM (tissue this far from every moved bone held at rest;
// 0: none; default the pose's), --hold-unmoved-bones (the unmoved parts'
// bones held at rest in the steps, not soft targets), --no-untangle (no
// untangling after the last step), --contact-rounds N, --no-contact-faces
// (the contact by the boundary's vertices alone, not its faces' centroids), --no-contact-sides
// (the contact by rest distance alone, not across the limb cuts' sides), --contact-radius
// MM, --contact-weight W (the contact after it; 0 rounds: none),
// --owner-shell V (ownerShellVoxels), --wrist-bodies (a sphere body at each wrist),
// --leg-trunk-cut none|front|all (where each leg is cut from the trunk),
// --leg-trunk-behind MM (front: how far behind the hip's centre),
// --no-tissue-bones-held (the trunk's and pelvis' bones left to the tissue
// solved with it, not held at rest: tissueBoneParts), --attachment-angle DEG (the bodies'
// attachment half angle), --elbow-attachment-angle DEG (the elbows' alone), --untangle-radius MM (one radius instead of the
// pose's), --whole-part-bone-clearance MM (the
// hands', feet's and head's tissue this near another part's bone soft; 0:
// only within the joint's clearance), --whole-part-own-bone-clearance MM
// (their own bones this near another part's bone soft), --knee-forward MM (both knees' centres moved MM along the body's front
// before the mesh is built: how the hinge's axis, which the skeleton clears
// of the bones over the knee's range, serves the tissue).
// Prints a table, then one JSON line (prefix "json ") for scripts.

#include "geometry/deform/articulated_mesh.h"
#include "geometry/deform/articulated_pose.h"
#include "geometry/deform/pose/pose.h"
#include "geometry/error.h"
#include "geometry/io/grid_io.h"
#include "geometry/organ_table.h"
#include "geometry/skeleton/skeleton.h"
#include "geometry/synth.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <sstream>
#include <string>

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

int usage() {
  std::fprintf(stderr,
               "usage: articulated_pose_bench GRID ORGANS POSE [--steps N] [--bone-weight W] [--sliding-weight W] [--max-iterations N] "
               "[--volume-weight L] [--direct-limit N] [--scapulae] [--wrist-bodies] [--bone-gap MM] [--bone-gap-reach MM] [--bone-gap-joints J,J...] [--bone-gap-opens-skin] [--bone-gap-beside-cuts] [--cut-off-tissue-rigid] [--cut-off-tissue-held] [--bone-gap-keeps-cut-faces] [--leg-trunk-cut none|front|all] [--leg-trunk-behind MM] [--no-tissue-bones-held] [--yielding-shell V] [--yielding-hips] [--squeezed F] [--dump PREFIX] [--mesh-only] "
               "[--knee-forward MM] [--trunk-reach MM] [--pelvis-reach MM] [--joint-clearance MM] [--still-beyond MM] [--hold-unmoved-bones] [--no-untangle] [--contact-rounds N] [--no-contact-faces] [--no-contact-sides] [--contact-radius MM] [--contact-weight W] [--owner-shell V] [--attachment-angle DEG] [--elbow-attachment-angle DEG] [--untangle-radius MM] [--whole-part-bone-clearance MM] [--whole-part-own-bone-clearance MM]\n"
               "       articulated_pose_bench --figure POSE [options]\n");
  return 2;
}

// Where the tissue locks: the tets of `mesh` under `below` of their rest
// volume in `posed`, by the joint nearest their rest centroid (in front of
// it or behind, within 30 mm or beyond) and by what their vertices are: the
// rigid parts among them, sliding vertices, free ones.
void squeezedTets(const vox::ArticulatedMesh& mesh, const vox::skeleton::Skeleton& sk, int step,
                  std::span<const Eigen::Vector3d> posed, double below) {
  using namespace vox;
  const std::vector<Eigen::Vector3d>& rest = mesh.mesh.positions;
  const std::vector<Eigen::Vector3d> now(posed.begin(), posed.end());
  std::map<std::string, std::size_t> where, what;
  std::size_t count = 0;
  double worst = 1.0;
  std::string worstText;
  std::vector<std::pair<double, std::string>> listed;
  for (std::size_t ti = 0; ti < mesh.mesh.tets.size(); ++ti) {
    const Tet& t = mesh.mesh.tets[ti];
    // A tet of one part's bones only moves rigidly at the end; on the way
    // its vertices follow the solve's, and it is not in the solve.
    if (rigidWithOneSegment(mesh, t)) continue;
    const double r = signedVolume(now, t) / signedVolume(rest, t);
    if (r >= below) continue;
    ++count;
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const std::int32_t v : t) c += 0.25 * rest[std::size_t(v)];
    const skeleton::Joint* joint = sk.nearestJoint(c);
    const Eigen::Vector3d d = joint ? Eigen::Vector3d(c - joint->centre) : Eigen::Vector3d::Zero();
    std::string at = "none";
    if (joint) {
      at = std::string(joint->kind().name) + (d.dot(joint->anterior) >= 0.0 ? " front" : " back") + (d.norm() >= 30.0 ? " far" : " near");
    }
    ++where[at];
    std::set<std::string> parts;
    int sliding = 0, free = 0;
    for (const std::int32_t v : t) {
      const auto k = std::size_t(v);
      if (mesh.role[k] == VertexRole::Rigid) parts.insert(segmentName(int(mesh.vertexPart[k])));
      else if (mesh.role[k] == VertexRole::Sliding) ++sliding;
      else ++free;
    }
    std::string kind = std::to_string(parts.size()) + " parts";
    for (const std::string& p : parts) kind += " " + p;
    kind += sliding ? " +sliding" : "";
    kind += free ? " +free" : "";
    const std::int32_t tag = mesh.mesh.labels.empty() ? 0 : mesh.mesh.labels[ti];
    kind += tag == kSoftTissueTag ? " (tissue tet)" : tag >= kBodyTag ? " (body tet)" : " (bone tet)";
    ++what[kind];
    if (joint) {
      char line[256];
      std::snprintf(line, sizeof line, "%s: %.0f mm from the centre (radius %.0f), along the bone %.0f, front %.0f, right %.0f; %s",
                    joint->kind().name, d.norm(), joint->radius, d.dot(joint->longAxis), d.dot(joint->anterior), d.dot(joint->leftRight),
                    kind.c_str());
      listed.emplace_back(r, line);
    }
    if (r < worst) {
      worst = r;
      worstText = at + ", " + kind + ", rest centroid " + std::to_string(c.x()) + " " + std::to_string(c.y()) + " " + std::to_string(c.z());
    }
  }
  std::printf("step %d: %zu tets under %.3f of rest volume; worst %.4f at %s\n", step, count, below, worst, worstText.c_str());
  const auto top = [](const std::map<std::string, std::size_t>& m, const char* title) {
    std::vector<std::pair<std::size_t, std::string>> v;
    for (const auto& [k, n] : m) v.emplace_back(n, k);
    std::sort(v.rbegin(), v.rend());
    std::printf("  %s:", title);
    for (std::size_t i = 0; i < v.size() && i < 6; ++i) std::printf(" [%s] %zu;", v[i].second.c_str(), v[i].first);
    std::printf("\n");
  };
  top(where, "where");
  top(what, "what");
  std::sort(listed.begin(), listed.end());
  for (std::size_t i = 0; i < listed.size() && i < 12; ++i) std::printf("    %.3f %s\n", listed[i].first, listed[i].second.c_str());
}

}  // namespace

// The mesh as raw arrays for numpy (np.fromfile): PREFIX.tets (int32 x4),
// PREFIX.tags (int32), PREFIX.roles and PREFIX.parts (uint8 per vertex), PREFIX.bodies (int8 per
// vertex: the body a sliding vertex stays on, else -1),
// PREFIX.WHICH (float64 x3 per vertex: rest, stepN after the pose's step N, or posed positions).
void dumpMesh(const std::string& prefix, const vox::ArticulatedMesh& mesh, std::span<const Eigen::Vector3d> positions,
              const std::string& which) {
  const auto write = [&](const std::string& suffix, const void* data, std::size_t bytes) {
    std::FILE* f = std::fopen((prefix + "." + suffix).c_str(), "wb");
    if (!f || std::fwrite(data, 1, bytes, f) != bytes) throw std::runtime_error("cannot write " + prefix + "." + suffix);
    std::fclose(f);
  };
  write(which, positions.data(), positions.size() * sizeof(Eigen::Vector3d));
  if (which != "rest") return;
  write("tets", mesh.mesh.tets.data(), mesh.mesh.tets.size() * sizeof(vox::Tet));
  write("tags", mesh.mesh.labels.data(), mesh.mesh.labels.size() * sizeof(std::int32_t));
  write("roles", mesh.role.data(), mesh.role.size());
  write("parts", mesh.vertexPart.data(), mesh.vertexPart.size());
  write("bodies", mesh.vertexBody.data(), mesh.vertexBody.size());
}

int main(int argc, char** argv) {
  using namespace vox;
  std::vector<std::string> positional;
  ArticulatedPoseOptions poseOptions;
  bool noContactSides = false, noTissueBonesHeld = false;
  ArticulatedMeshOptions meshOptions;
  bool figure = false;
  double squeezedBelow = 0.0;
  std::string dumpPrefix;
  bool meshOnly = false;
  double kneeForwardMm = 0.0;
  int stepsGiven = 0;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    const auto value = [&]() -> std::string {
      if (a + 1 >= argc) std::exit(usage());
      return argv[++a];
    };
    if (arg == "--figure") figure = true;
    else if (arg == "--steps") stepsGiven = std::stoi(value());
    else if (arg == "--bone-weight") poseOptions.boneWeight = std::stod(value());
    else if (arg == "--sliding-weight") poseOptions.slidingWeight = std::stod(value());
    else if (arg == "--max-iterations") poseOptions.solve.maxIterations = std::stoi(value());
    else if (arg == "--volume-weight") poseOptions.solve.volumeWeight = std::stod(value());
    else if (arg == "--direct-limit") poseOptions.solve.directSolveLimit = std::stoll(value());
    else if (arg == "--yielding-hips") {
      meshOptions.yieldingShellJoints.push_back(skeleton::JointId::RightHip);
      meshOptions.yieldingShellJoints.push_back(skeleton::JointId::LeftHip);
    }
    else if (arg == "--squeezed") squeezedBelow = std::stod(value());
    else if (arg == "--dump") dumpPrefix = value();
    else if (arg == "--mesh-only") meshOnly = true;
    else if (arg == "--knee-forward") kneeForwardMm = std::stod(value());
    else if (arg == "--scapulae") meshOptions.movingScapulae = true;
    else if (arg == "--wrist-bodies") meshOptions.wristBodies = true;
    else if (arg == "--bone-gap") meshOptions.boneGapMm = std::stod(value());
    else if (arg == "--bone-gap-reach") meshOptions.boneGapReachMm = std::stod(value());
    else if (arg == "--bone-gap-opens-skin") meshOptions.boneGapKeepsSkin = false;
    else if (arg == "--bone-gap-beside-cuts") meshOptions.boneGapBesideCuts = true;
    else if (arg == "--cut-off-tissue-rigid") {
      meshOptions.boneGapBesideCuts = true;
      meshOptions.cutOffTissueRigid = true;
    }
    else if (arg == "--cut-off-tissue-held") meshOptions.cutOffTissueRigid = false;
    else if (arg == "--bone-gap-keeps-cut-faces") meshOptions.boneGapBesideCuts = false;
    else if (arg == "--bone-gap-joints") {
      meshOptions.boneGapJoints.clear();
      std::stringstream names(value());
      for (std::string name; std::getline(names, name, ',');) {
        const std::optional<skeleton::JointId> j = skeleton::jointFromName(name);
        if (!j) return usage();
        meshOptions.boneGapJoints.push_back(*j);
      }
    }
    else if (arg == "--leg-trunk-cut") {
      const std::string v = value();
      using enum ArticulatedMeshOptions::LegTrunkCut;
      meshOptions.legTrunkCut = v == "none" ? None : v == "all" ? All : Front;
    } else if (arg == "--leg-trunk-behind") meshOptions.legTrunkCutBehindMm = std::stod(value());
    else if (arg == "--no-tissue-bones-held") noTissueBonesHeld = true;
    else if (arg == "--yielding-shell") meshOptions.yieldingShellVoxels = std::stod(value());
    else if (arg == "--trunk-reach") meshOptions.trunkBoneReachMm = std::stod(value());
    else if (arg == "--pelvis-reach") meshOptions.pelvisBoneReachMm = std::stod(value());
    else if (arg == "--still-beyond") poseOptions.stillBeyondMm = std::stod(value());
    else if (arg == "--hold-unmoved-bones") poseOptions.holdUnmovedBones = true;
    else if (arg == "--no-untangle") poseOptions.untangleRadiiMm.clear();
    else if (arg == "--contact-rounds") poseOptions.contactRounds = std::stoi(value());
    else if (arg == "--no-contact-faces") poseOptions.contact.faceCentroids = false;
    else if (arg == "--no-contact-sides") noContactSides = true;
    else if (arg == "--contact-radius") poseOptions.contactRadiusMm = std::stod(value());
    else if (arg == "--contact-weight") poseOptions.contactWeight = std::stod(value());
    else if (arg == "--contact-margin") poseOptions.contactMarginMm = std::stod(value());
    else if (arg == "--whole-part-bone-clearance") meshOptions.wholePartBoneClearanceMm = std::stod(value());
    else if (arg == "--whole-part-own-bone-clearance") meshOptions.wholePartOwnBoneClearanceMm = std::stod(value());
    else if (arg == "--joint-clearance") meshOptions.jointClearanceMm = std::stod(value());
    else if (arg == "--owner-shell") meshOptions.ownerShellVoxels = std::stod(value());
    else if (arg == "--attachment-angle") meshOptions.attachmentHalfAngleDeg = std::stod(value());
    else if (arg == "--elbow-attachment-angle") meshOptions.elbowAttachmentHalfAngleDeg = std::stod(value());
    else if (arg == "--untangle-radius") poseOptions.untangleRadiiMm = {std::stod(value())};
    else if (arg.starts_with("--")) return usage();
    else positional.push_back(arg);
  }
  if (positional.size() != (figure ? 1u : 3u)) return usage();
  try {
    const auto t0 = Clock::now();
    const LabelGrid grid = figure ? synthesize(SynthKind::SkeletonFigure, 96) : readGrid(positional[0]);
    const OrganTable organs = figure ? synthOrganTable(SynthKind::SkeletonFigure) : OrganTable::read(positional[1]);
    const std::string posePath = positional.back();
    const Pose pose = readPose(posePath);
    if (pose.joints.empty()) throw InputError(posePath, "the pose has no \"joints\"");
    skeleton::Skeleton sk = skeleton::buildSkeleton(
        grid, organs, figure ? skeleton::SkeletonSources{"figure", "figure organs", "figure parts"} : skeleton::SkeletonSources{});
    if (kneeForwardMm != 0.0)
      for (skeleton::Joint& j : sk.joints)
        if (j.id == skeleton::JointId::RightKnee || j.id == skeleton::JointId::LeftKnee) {
          j.centre += kneeForwardMm * j.anterior;
          std::printf("%s: centre moved %.1f mm to the front\n", j.kind().name, kneeForwardMm);
        }
    const std::vector<skeleton::Joint> joints = skeleton::posedJoints(sk, pose.joints, posePath);
    const double skeletonSeconds = secondsSince(t0);

    const auto t1 = Clock::now();
    const ArticulatedMesh mesh = buildArticulatedMesh(grid, organs, sk, meshOptions);
    const double meshSeconds = secondsSince(t1);
    std::printf("mesh: %zu vertices, %zu tets, %zu bodies, built in %.1f s (skeleton %.1f s); bone-gap cut %zu faces; %zu cut-off tissue vertices rigid\n",
                mesh.mesh.vertexCount(), mesh.mesh.tetCount(), mesh.bodies.size(), meshSeconds, skeletonSeconds, mesh.boneGapCut.cutFaces,
                mesh.cutOffTissueVertices);

    for (const ArticularBody& b : mesh.bodies) {
      std::printf("  body %s: %s radius %.1f mm", skeleton::jointKind(b.joint).name,
                  b.shape == ArticularShape::Sphere ? "sphere" : "cylinder", b.radius);
      if (b.shape == ArticularShape::Cylinder) std::printf(", half length %.1f mm", b.halfLength);
      std::printf("\n");
    }
    if (!dumpPrefix.empty()) dumpMesh(dumpPrefix, mesh, mesh.mesh.positions, "rest");
    if (meshOnly) return 0;

    if (squeezedBelow > 0.0 || !dumpPrefix.empty()) poseOptions.onStep = [&](int step, std::span<const Eigen::Vector3d> posed) {
      if (squeezedBelow > 0.0) squeezedTets(mesh, sk, step, posed, squeezedBelow);
      if (!dumpPrefix.empty()) dumpMesh(dumpPrefix, mesh, posed, "step" + std::to_string(step));
    };
    poseOptions.steps = stepsGiven > 0 ? stepsGiven : articulatedPoseSteps(pose.joints, poseOptions);
    if (!noContactSides) poseOptions.contact.side = limbGroupSides(mesh, sk);
    if (!noTissueBonesHeld) {
      const auto t2 = Clock::now();
      poseOptions.tissueBoneParts = tissueBoneParts(mesh, grid, organs, sk, meshOptions);
      std::printf("pelvis' bones left to the tissue: %zu vertices held, found in %.2f s\n",
                  std::size_t(std::count_if(poseOptions.tissueBoneParts.begin(), poseOptions.tissueBoneParts.end(),
                                            [](skeleton::Part p) { return p != skeleton::Part::None; })),
                  secondsSince(t2));
    }
    ArticulatedPoser poser(mesh, poseOptions);
    const ArticulatedPoseReport r = poser.pose(jointMotionPath(sk, joints, pose.joints, mesh));
    std::printf("pose: %d steps, %d iterations, %.1f s; solved %zu vertices, %zu tets (still: %zu vertices held, %zu tets left out)\n",
                r.steps, r.iterations, r.seconds, r.solvedVertices, r.solvedTets, r.stillVertices, r.stillTets);
    std::printf("step  min det J  bones' lag (mm)\n");
    for (std::size_t s = 0; s < r.stepMinRelativeVolume.size(); ++s)
      std::printf("%4zu  %9.4f  %s\n", s + 1, r.stepMinRelativeVolume[s],
                  s < r.stepBoneLagMm.size() ? std::to_string(r.stepBoneLagMm[s]).c_str() : "(last step: hard)");
    std::printf("lag after the approach (mm):");
    nlohmann::json lag = nlohmann::json::object();
    for (std::size_t p = 0; p < r.segmentLagMm.size(); ++p)
      if (r.segmentLagMm[p] > 0.05) {
        std::printf(" %s %.1f", segmentName(int(p)), r.segmentLagMm[p]);
        lag[segmentName(int(p))] = r.segmentLagMm[p];
      }
    std::printf("\n");

    // Inverted tets in the final positions, by the joint nearest their rest centroid.
    const std::vector<Eigen::Vector3d>& posed = poser.positions();
    if (!dumpPrefix.empty()) dumpMesh(dumpPrefix, mesh, posed, "posed");
    // Where, in the nearest joint's frame (rest): in front of the joint's
    // centre or behind it, and within 30 mm of it or farther.
    std::map<std::string, std::size_t> byJoint;
    std::map<std::string, std::array<std::size_t, 4>> where;  // front near, front far, back near, back far
    for (const Tet& t : mesh.mesh.tets) {
      if (signedVolume(posed, t) > 0.0) continue;
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (const std::int32_t v : t) c += 0.25 * mesh.mesh.positions[std::size_t(v)];
      const skeleton::Joint* joint = sk.nearestJoint(c);
      if (!joint) continue;
      const Eigen::Vector3d d = c - joint->centre;
      ++byJoint[joint->kind().name];
      ++where[joint->kind().name][(d.dot(joint->anterior) >= 0.0 ? 0 : 2) + (d.norm() >= 30.0 ? 1 : 0)];
    }
    std::printf("inverted tets: %zu (bones reached their motions: %s); before untangling %zu, untangled %zu vertices within %.0f mm in %.1f s; final smallest det J %.4f\n",
                r.invertedTets, r.reachedTargets ? "yes" : "no", r.invertedBeforeUntangling, r.untangledVertices, r.untangleRadiusMm,
                r.untangleSeconds, r.finalMinRelativeVolume);
    std::printf("contact: %zu boundary vertices through the tissue across before (deepest %.2f mm), %zu after %d rounds (%.2f mm; %zu vertices moved) in %.1f s\n",
                r.penetratingBeforeContact, r.deepestPenetrationBeforeMm, r.penetratingAfterContact, r.contactRounds,
                r.deepestPenetrationAfterMm, r.contactVertices, r.contactSeconds);
    for (const auto& [name, n] : byJoint) {
      const auto& w = where[name];
      std::printf("  %-16s %6zu: in front %zu within 30 mm, %zu beyond; behind %zu within 30 mm, %zu beyond\n", name.c_str(), n,
                  w[0], w[1], w[2], w[3]);
    }

    nlohmann::json out = {{"pose", posePath},
                          {"tets", mesh.mesh.tetCount()},
                          {"mesh_seconds", meshSeconds},
                          {"pose_seconds", r.seconds},
                          {"steps", r.steps},
                          {"iterations", r.iterations},
                          {"inverted_tets", r.invertedTets},
                          {"inverted_before_untangling", r.invertedBeforeUntangling},
                          {"untangled_vertices", r.untangledVertices},
                          {"untangle_radius_mm", r.untangleRadiusMm},
                          {"untangle_seconds", r.untangleSeconds},
                          {"penetrating_before_contact", r.penetratingBeforeContact},
                          {"penetrating_after_contact", r.penetratingAfterContact},
                          {"deepest_penetration_before_mm", r.deepestPenetrationBeforeMm},
                          {"deepest_penetration_after_mm", r.deepestPenetrationAfterMm},
                          {"contact_seconds", r.contactSeconds},
                          {"final_min_relative_volume", r.finalMinRelativeVolume},
                          {"inverted_by_joint", byJoint},
                          {"reached_targets", r.reachedTargets},
                          {"min_relative_volume", r.minRelativeVolume},
                          {"step_min_relative_volume", r.stepMinRelativeVolume},
                          {"step_bone_lag_mm", r.stepBoneLagMm},
                          {"segment_lag_mm", lag},
                          {"max_sliding_gap_mm", r.maxSlidingGapMm}};
    std::cout << "json " << out.dump() << std::endl;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "articulated_pose_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
