#include "geometry/deform/report/deformation_report.h"

#include "geometry/skeleton/body_parts.h"
#include "geometry/skeleton/bones.h"

#include <nlohmann/json.hpp>

#include <cmath>

// The JSON report of `voxmorph deform` (docs/POSES.md lists its fields).

namespace vox {

namespace {

using nlohmann::json;

json toJson(const EdgeDistortion& d) { return {{"edges", d.edges}, {"mean", d.mean}, {"median", d.median}, {"p95", d.p95}, {"max", d.max}}; }

json toJson(const DistortionHistogram& h) {
  return {{"lo", h.lo},     {"hi", h.hi},   {"bins", h.fractions}, {"below", h.below},
          {"above", h.above}, {"mean", h.mean}, {"min", h.min},   {"max", h.max}, {"rms_deviation", h.rmsDeviation}};
}

json toJson(const BodyProjection& p) {
  return {{"front_area_mm2", p.frontMm2}, {"side_area_mm2", p.sideMm2}, {"top_area_mm2", p.topMm2}, {"height_mm", p.heightMm},
          {"foreground_voxels", p.foregroundVoxels}, {"exact", p.exact}};
}

json toJson(const GridGeometry& g) {
  return {{"dims", {g.dims[0], g.dims[1], g.dims[2]}},
          {"spacing_mm", {g.spacing.x(), g.spacing.y(), g.spacing.z()}},
          {"origin_mm", {g.origin.x(), g.origin.y(), g.origin.z()}},
          {"voxels", g.voxelCount()}};
}

}  // namespace

std::string deformationReportJson(const DeformationReport& r) {
  json root;
  root["input"] = r.input;
  root["output"] = r.output;
  root["pose"] = r.pose;
  root["engine"] = r.engine;
  root["source_grid"] = toJson(r.source);
  root["posed_grid"] = toJson(r.posed);
  root["working_grid"] = {{"downsample_factor", r.workingFactor}, {"voxels", r.workingVoxels}};
  root["max_memory_bytes"] = r.maxMemoryBytes;
  root["samples"] = r.samples;

  json stages = json::array();
  double wall = 0, cpu = 0;
  for (const StageTime& t : r.stages) {
    stages.push_back({{"stage", t.name}, {"seconds", t.seconds}, {"cpu_seconds", t.cpuSeconds}});
    wall += t.seconds;
    cpu += t.cpuSeconds;
  }
  root["stages"] = stages;
  root["total_seconds"] = wall;
  root["total_cpu_seconds"] = cpu;

  root["cage"] = {{"automatic", r.automaticCage},
                  {"vertices", r.cageVertices},
                  {"faces", r.cageFaces},
                  {"meshed_vertices_before_qem", r.cage.meshedVertices},
                  {"eroded_voxels", r.cage.erodedVoxels},
                  {"valid", r.cage.check.validCage()},
                  {"genus", r.cage.check.genus},
                  {"self_intersections", r.cage.check.selfIntersections},
                  {"volume_mm3", r.cage.check.volume}};
  json selections = json::array();
  for (const auto& [name, vertices] : r.selections) selections.push_back({{"name", name}, {"cage_vertices", vertices}});
  root["selections"] = selections;
  root["envelope"] = {{"vertices", r.envelopeVertices}, {"faces", r.envelopeFaces}, {"vertices_outside_cage", r.envelopeOutside}};
  json cuts = json::array();
  for (const CutReport& c : r.cuts)
    cuts.push_back({{"cut_faces", c.cutFaces}, {"duplicated_vertices", c.duplicatedVertices}, {"opened_rim_faces", c.openedRimFaces}, {"contact_vertices", c.contactVertices}});
  root["transfer_mesh"] = {{"vertices", r.tmVertices},
                           {"tets", r.tmTets},
                           {"vertices_inside_cage", r.tmInside},
                           {"vertices_outside_cage", r.tmOutside},
                           {"uncovered_foreground_voxels", r.uncoveredVoxels},
                           {"tets_inverted_by_deformation", r.tmInverted},
                           {"inverted_rest_volume_fraction", r.tmInvertedVolumeFraction},
                           {"cuts", cuts}};
  root["outliers"] = {{"transfer_mesh_vertices_outside_cage", r.tmOutside},
                      {"foreground_voxels_outside_cage", r.foregroundOutsideCage},
                      {"edge_length_distortion",
                       {{"outside", toJson(r.outlierDistortion.outside)},
                        {"inside_nearby", toJson(r.outlierDistortion.insideNearby)},
                        {"inside", toJson(r.outlierDistortion.inside)}}}};

  json steps = json::array();
  for (std::size_t k = 0; k < r.refinement.steps.size(); ++k) {
    const RefinementStep& s = r.refinement.steps[k];
    steps.push_back({{"iteration", k},
                     {"vertices", s.vertices},
                     {"tets", s.tets},
                     {"mean_error", s.meanError},
                     {"max_error", s.maxError},
                     {"split_edges", s.splitEdges},
                     {"seconds", s.seconds}});
  }
  root["refinement"] = {{"iterations", steps}, {"kept", r.refinement.kept}, {"stop", r.refinement.stopReason}};
  root["distortion"] = {{"volume_mm3", r.distortion.volume},
                        {"angle_deg", toJson(r.distortion.angle)},
                        {"stretch", toJson(r.distortion.stretch)}};

  json labels = json::array();
  json small = json::array();
  double largest = 0;
  json largestLabel = nullptr;
  for (const LabelChange& c : r.labels) {
    json j = {{"label", c.label}, {"voxels_before", c.before}, {"voxels_after", c.after}, {"volume_change_pct", c.volumeChangePercent}};
    if (!c.name.empty()) j["name"] = c.name;
    if (c.unnamed) j["unnamed"] = true;
    if (c.deformedVolumeVoxels >= 0) j["deformed_volume_voxels"] = c.deformedVolumeVoxels;
    if (r.withMasses) {
      j["mass_before_g"] = c.massBeforeGrams;
      j["mass_after_g"] = c.massAfterGrams;
      j["mass_change_pct"] = c.volumeChangePercent;
    }
    labels.push_back(std::move(j));
    if (c.before < kSmallOrganVoxels) {
      small.push_back({{"label", c.label}, {"name", c.name}, {"voxels_before", c.before}, {"change_pct", c.volumeChangePercent}});
    } else if (std::abs(c.volumeChangePercent) > std::abs(largest) || largestLabel.is_null()) {
      largest = c.volumeChangePercent;
      largestLabel = {{"label", c.label}, {"name", c.name}, {"change_pct", c.volumeChangePercent}};
    }
  }
  root["labels"] = labels;
  root["small_labels"] = {{"threshold_voxels", kSmallOrganVoxels}, {"labels", small}};
  root["largest_change_above_threshold"] = largestLabel;
  json whole = {{"voxels_before", r.wholeBody.before},
                {"voxels_after", r.wholeBody.after},
                {"volume_change_pct", r.wholeBody.volumeChangePercent}};
  if (r.withMasses) {
    whole["mass_before_g"] = r.wholeBody.massBeforeGrams;
    whole["mass_after_g"] = r.wholeBody.massAfterGrams;
    whole["mass_change_pct"] = r.wholeBody.massChangePercent;
  }
  root["whole_body"] = whole;
  root["forced"] = r.forced;
  root["body_projection"] = {
      {"frame", "world, RAS+ (x to the subject's right, y anterior, z superior); front: along y onto the x-z plane, side: "
                "along x onto the y-z plane, top: along z onto the x-y plane; height: extent along z"},
      {"rest", toJson(r.restProjection)},
      {"posed", toJson(r.posedProjection)}};
  root["provenance"] = json::parse(provenanceJson(r.provenance));
  if (!r.bones.empty()) {
    json bones = json::array();
    for (const BoneRigidity& b : r.bones)
      bones.push_back({{"part", skeleton::partName(skeleton::Part(b.key / kBoneKeyStride))},
                       {"bone", skeleton::boneName(skeleton::Bone(b.key % kBoneKeyStride))},
                       {"voxels", b.voxels},
                       {"tm_tets", b.tets},
                       {"tm_vertices", b.vertices},
                       {"rigid_vertices", r.rigidGroups > 0 ? b.rigidVertices : 0},
                       {"tm_edges", b.edges},
                       {"max_strain", b.maxStrain},
                       {"volume_rest_ml", b.restVolumeMm3 * 1e-3},
                       {"volume_posed_ml", b.posedVolumeMm3 * 1e-3},
                       {"volume_change_percent", b.volumeChangePercent()}});
    root["bones"] = {{"held_rigid", r.rigidGroups > 0},
                     {"rigid_groups", r.rigidGroups},
                     {"rigid_vertices", r.rigidVertices},
                     {"free_joint_vertices", r.sharedBoneVertices},
                     {"uncovered_bone_voxels", r.uncoveredBoneVoxels},
                     {"per_bone", bones}};
  }
  if (!r.partTransforms.empty()) {
    nlohmann::json parts = nlohmann::json::array();
    for (const auto& [name, m] : r.partTransforms) {
      nlohmann::json rows = nlohmann::json::array();
      for (int row = 0; row < 4; ++row) rows.push_back({m(row, 0), m(row, 1), m(row, 2), m(row, 3)});
      parts.push_back({{"part", name}, {"matrix", rows}});
    }
    root["part_transforms"] = parts;
  }
  if (const auto& a = r.articulated)
    root["articulated"] = {{"vertices", a->vertices},
                           {"tets", a->tets},
                           {"articular_bodies", a->bodies},
                           {"body_cut_faces", a->bodyCutFaces},
                           {"limb_cut_faces", a->limbCutFaces},
                           {"bone_gap_cut_faces", a->boneGapCutFaces},
                           {"cut_off_tissue_vertices", a->cutOffTissueVertices},
                           {"rigid_vertices", a->rigidVertices},
                           {"sliding_vertices", a->slidingVertices},
                           {"solved_vertices", a->solvedVertices},
                           {"still_vertices", a->stillVertices},
                           {"still_tets", a->stillTets},
                           {"solved_tets", a->solvedTets},
                           {"steps", a->steps},
                           {"iterations", a->iterations},
                           {"min_relative_volume", a->minRelativeVolume},
                           {"inverted_tets", a->invertedTets},
                           {"bones_on_their_motions", a->reachedTargets},
                           {"max_sliding_gap_mm", a->maxSlidingGapMm},
                           {"untangling", {{"inverted_tets_before", a->invertedBeforeUntangling},
                                           {"moved_vertices", a->untangledVertices},
                                           {"radius_mm", a->untangleRadiusMm},
                                           {"seconds", a->untangleSeconds}}},
                           {"contact", {{"penetrating_vertices_before", a->penetratingBeforeContact},
                                        {"penetrating_vertices_after", a->penetratingAfterContact},
                                        {"deepest_mm_before", a->deepestPenetrationBeforeMm},
                                        {"deepest_mm_after", a->deepestPenetrationAfterMm},
                                        {"rounds", a->contactRounds},
                                        {"moved_vertices", a->contactVertices},
                                        {"seconds", a->contactSeconds}}},
                           {"final_min_relative_volume", a->finalMinRelativeVolume}};
  if (const auto& c = r.collisions) {
    json pairs = json::array();
    for (const CollisionPair& p : c->pairs)
      pairs.push_back({{"parts", {skeleton::partName(skeleton::Part(p.partA)), skeleton::partName(skeleton::Part(p.partB))}},
                       {"voxels", p.voxels},
                       {"volume_ml", double(p.voxels) * c->lattice.voxelVolume() * 1e-3}});
    json contacts = json::array();
    for (const ContactPair& p : c->contacts)
      contacts.push_back({{"parts", {skeleton::partName(skeleton::Part(p.partA)), skeleton::partName(skeleton::Part(p.partB))}},
                          {"area_cm2", p.areaMm2 * 1e-2}});
    root["collisions"] = {{"lattice", toJson(c->lattice)},
                          {"body_voxels", c->bodyVoxels},
                          {"voxels", c->voxels},
                          {"volume_ml", c->volumeMm3() * 1e-3},
                          {"body_fraction", c->bodyFraction()},
                          {"pairs", pairs},
                          {"contacts", contacts}};
  }
  root["warnings"] = deformationWarnings(r);
  if (const auto& c = r.volumeCorrection)
    root["volume_correction"] = {{"targets", c->toRestVolumes ? "rest" : "deformed"},
                                 {"boundary_voxels", c->candidates},
                                 {"relabelled_voxels", c->relabelled},
                                 {"still_boundary_voxels_kept", c->still},
                                 {"gap_voxels_filled", c->gapsFilled},
                                 {"sweeps", c->sweeps},
                                 {"deviation_before_voxels", c->deviationBefore},
                                 {"deviation_after_voxels", c->deviationAfter},
                                 {"worst_label_pct_before", c->worstPercentBefore},
                                 {"worst_label_pct_after", c->worstPercentAfter}};
  if (const auto& c = r.skinCover) {
    nlohmann::json from = nlohmann::json::array(), to = nlohmann::json::array();
    for (std::size_t l = 0; l < c->from.size(); ++l)
      if (c->from[l] > 0) from.push_back({{"label", l}, {"voxels", c->from[l]}});
    for (std::size_t l = 0; l < c->to.size(); ++l)
      if (c->to[l] > 0) to.push_back({{"label", l}, {"voxels", c->to[l]}});
    root["skin_cover"] = {{"bare_voxels", c->bareVoxels},
                          {"bare_at_rest_kept", c->bareAtRest},
                          {"bone_voxels_bare", c->boneVoxels},
                          {"covered_voxels", c->covered},
                          {"skin_over_bone_voxels", c->overBone},
                          {"from", from},
                          {"to", to}};
  }
  return root.dump(2) + "\n";
}

}  // namespace vox
