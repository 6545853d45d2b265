#include "geometry/remesh/remesh_report.h"

#include "geometry/progress.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace vox::remesh {

RemeshReport buildRemeshReport(const TetMesh& input, const MeshTopology& inputTopology, const TetMesh& output,
                               double targetLength, const RemeshStats& stats, const ReportOptions& options) {
  reportProgress("quality report", 0.0);
  RemeshReport r;
  r.targetLength = targetLength;
  r.stats = stats;
  for (std::int32_t l : input.labels) r.inputTets += l > 0;
  r.outputVertices = output.vertexCount();
  r.quality = summarizeTetQuality(output);
  r.outputTets = r.quality.tets;
  r.boundaryFacets = summarizeBoundaryFacets(output);
  r.edgeLengths = summarizeEdgeLengths(output, targetLength);
  const TetQualitySummary inputQuality = summarizeTetQuality(input);
  const MeshTopology outputTopology = computeMeshTopology(output);
  r.topologyDifferences = compareTopology(inputTopology, outputTopology);
  reportProgress("quality report", 0.5);
  r.junctionCurveSets = inputTopology.junctionCurves.size();
  r.junctionPointSets = inputTopology.junctionPoints.size();
  r.named = options.named || !output.labelNames.empty();
  std::map<std::int32_t, InterfaceDistance> distances;
  if (options.distances) {
    distances = interfaceDistances(input, output, options.maxDistanceSamples, options.threads);
    r.distancesMeasured = true;
  }
  for (const auto& [label, topo] : inputTopology.labels) {
    LabelReport lr;
    lr.label = label;
    if (auto it = output.labelNames.find(label); it != output.labelNames.end()) lr.name = it->second;
    else if (r.named) r.unnamedLabels.push_back(label);
    lr.input = topo;
    if (auto it = outputTopology.labels.find(label); it != outputTopology.labels.end()) lr.output = it->second;
    lr.tets = lr.output.tets;
    if (auto it = inputQuality.volumePerLabel.find(label); it != inputQuality.volumePerLabel.end())
      lr.inputVolume = it->second;
    if (auto it = r.quality.volumePerLabel.find(label); it != r.quality.volumePerLabel.end()) lr.outputVolume = it->second;
    if (auto it = distances.find(label); it != distances.end()) lr.distance = it->second;
    r.labels.push_back(lr);
  }
  reportProgress("quality report", 1.0);
  return r;
}

namespace {
double relativeChange(double from, double to) { return from > 0.0 ? (to - from) / from : 0.0; }
}  // namespace

std::string reportText(const RemeshReport& r) {
  std::string s;
  char line[512];
  auto add = [&](const char* fmt, auto... args) {
    std::snprintf(line, sizeof line, fmt, args...);
    s += line;
  };
  add("target edge length   %.4g mm (e_min %.4g, e_max %.4g)\n", r.targetLength, 0.8 * r.targetLength,
      4.0 / 3.0 * r.targetLength);
  add("tets                 %zu (input %zu), %zu vertices\n", r.outputTets, r.inputTets, r.outputVertices);
  add("dihedral angles      min %.2f, max %.2f degrees; mean |angle - 70.5| %.2f\n", r.quality.minDihedral,
      r.quality.maxDihedral, r.quality.meanDeviationFrom70);
  add("slivers              %zu tets under 15 degrees, %zu under 5; %zu inverted\n", r.quality.under15, r.quality.under5,
      r.quality.inverted);
  add("boundary facets      %zu, angles %.2f to %.2f degrees, mean |angle - 60| %.2f\n", r.boundaryFacets.facets,
      r.boundaryFacets.minAngle, r.boundaryFacets.maxAngle, r.boundaryFacets.meanDeviationFrom60);
  add("edge lengths         %.3g to %.3g mm, mean %.3g, mean |length - l| / l %.1f%%\n", r.edgeLengths.minLength,
      r.edgeLengths.maxLength, r.edgeLengths.meanLength, 100.0 * r.edgeLengths.meanRelativeDeviation);
  double worstVolume = 0.0, worstDistance = 0.0, inTotal = 0.0, outTotal = 0.0;
  std::int32_t worstVolumeLabel = 0, worstDistanceLabel = 0;
  for (const LabelReport& l : r.labels) {
    const double c = std::abs(relativeChange(l.inputVolume, l.outputVolume));
    if (c > worstVolume) worstVolume = c, worstVolumeLabel = l.label;
    if (l.distance.hausdorff() > worstDistance) worstDistance = l.distance.hausdorff(), worstDistanceLabel = l.label;
    inTotal += l.inputVolume;
    outTotal += l.outputVolume;
  }
  add("volume               total change %+.2f%%, largest label change %.2f%% (label %d)\n",
      100.0 * relativeChange(inTotal, outTotal), 100.0 * worstVolume, worstVolumeLabel);
  if (r.distancesMeasured)
    add("interface distance   largest sampled Hausdorff %.3g mm (label %d)\n", worstDistance, worstDistanceLabel);
  add("topology             %s: %zu labels, 1-junctions of %zu label sets, 0-junctions of %zu label sets\n",
      r.topologyDifferences.empty() ? "preserved" : "CHANGED", r.labels.size(), r.junctionCurveSets, r.junctionPointSets);
  for (std::size_t i = 0; i < r.topologyDifferences.size() && i < 20; ++i) s += "  " + r.topologyDifferences[i] + "\n";
  add("time                 %.2f s remeshing (%.2f s reading and preparing the input; polish %zu vertices, %.2f s)\n",
      r.stats.seconds, r.setupSeconds, r.stats.polished, r.stats.polishSeconds);
  if (!r.unnamedLabels.empty()) {
    s += "unnamed labels      ";
    for (std::size_t i = 0; i < r.unnamedLabels.size(); ++i) s += (i ? ", " : " ") + std::to_string(r.unnamedLabels[i]);
    s += " (no name in the organ table)\n";
  }
  std::size_t nameWidth = r.named ? 9 : 0;  // at least "(unnamed)"
  if (r.named)
    for (const LabelReport& l : r.labels) nameWidth = std::max(nameWidth, std::min<std::size_t>(l.name.size(), 32));
  s += "label  " + (nameWidth ? (std::string("name") + std::string(nameWidth > 4 ? nameWidth - 4 : 0, ' ') + "  ") : std::string()) +
       "      tets   volume in -> out (mm^3)    change  comps  euler  hausdorff (mm)\n";
  for (const LabelReport& l : r.labels) {
    add("%5d  ", l.label);
    if (nameWidth) add("%-*.*s  ", int(nameWidth), int(nameWidth), l.name.empty() ? "(unnamed)" : l.name.c_str());
    add("%10zu  %12.1f -> %12.1f  %+7.2f%%  %2zu/%-2zu  %3lld/%-3lld", l.tets, l.inputVolume, l.outputVolume,
        100.0 * relativeChange(l.inputVolume, l.outputVolume), l.input.components, l.output.components,
        (long long)l.input.euler, (long long)l.output.euler);
    if (r.distancesMeasured) add("  %.3g", l.distance.hausdorff());
    s += "\n";
  }
  return s;
}

std::string reportJson(const RemeshReport& r) {
  nlohmann::json j;
  j["target_edge_length_mm"] = r.targetLength;
  j["tets"] = {{"input", r.inputTets}, {"output", r.outputTets}};
  j["vertices"] = r.outputVertices;
  j["dihedral_degrees"] = {{"min", r.quality.minDihedral},
                           {"max", r.quality.maxDihedral},
                           {"mean_deviation_from_70_5", r.quality.meanDeviationFrom70}};
  j["tets_under_15_degrees"] = r.quality.under15;
  j["tets_under_5_degrees"] = r.quality.under5;
  j["inverted_tets"] = r.quality.inverted;
  j["boundary_facets"] = {{"count", r.boundaryFacets.facets},
                          {"min_angle_degrees", r.boundaryFacets.minAngle},
                          {"max_angle_degrees", r.boundaryFacets.maxAngle},
                          {"mean_deviation_from_60", r.boundaryFacets.meanDeviationFrom60}};
  j["edge_lengths_mm"] = {{"count", r.edgeLengths.edges},
                          {"min", r.edgeLengths.minLength},
                          {"max", r.edgeLengths.maxLength},
                          {"mean", r.edgeLengths.meanLength},
                          {"mean_relative_deviation_from_target", r.edgeLengths.meanRelativeDeviation}};
  j["topology"] = {{"preserved", r.topologyDifferences.empty()},
                   {"differences", r.topologyDifferences},
                   {"junction_curve_label_sets", r.junctionCurveSets},
                   {"junction_point_label_sets", r.junctionPointSets}};
  j["interface_distance_method"] =
      r.distancesMeasured ? "largest point-to-surface distance from samples (vertices, edge mid-points, centroids) of "
                            "each label's boundary facets to the other mesh's, both ways; CGAL AABB tree"
                          : "not measured";
  nlohmann::json labels = nlohmann::json::array();
  for (const LabelReport& l : r.labels) {
    nlohmann::json e = {{"label", l.label},
                        {"tets", l.tets},
                        {"volume_mm3", {{"input", l.inputVolume}, {"output", l.outputVolume}}},
                        {"volume_change", relativeChange(l.inputVolume, l.outputVolume)},
                        {"components", {{"input", l.input.components}, {"output", l.output.components}}},
                        {"euler", {{"input", l.input.euler}, {"output", l.output.euler}}}};
    if (r.named) e["name"] = l.name.empty() ? nlohmann::json() : nlohmann::json(l.name);
    if (r.distancesMeasured)
      e["interface_distance_mm"] = {{"output_to_input", l.distance.outputToInput},
                                    {"input_to_output", l.distance.inputToOutput},
                                    {"hausdorff", l.distance.hausdorff()}};
    labels.push_back(e);
  }
  j["labels"] = labels;
  if (r.named) j["unnamed_labels"] = r.unnamedLabels;
  nlohmann::json steps = nlohmann::json::array();
  for (const RemeshStep& s : r.stats.steps)
    steps.push_back({{"name", s.name},
                     {"splits", s.splits},
                     {"collapses", s.collapses},
                     {"surface_flips", s.surfaceFlips},
                     {"inner_flips", s.innerFlips},
                     {"face_flips", s.faceFlips},
                     {"smoothed", {{"feature", s.smoothedFeature}, {"surface", s.smoothedSurface}, {"inside", s.smoothedInside}}},
                     {"tets", s.tets},
                     {"seconds", {{"split", s.splitSeconds}, {"collapse", s.collapseSeconds}, {"flip", s.flipSeconds},
                                  {"smooth", s.smoothSeconds}, {"total", s.seconds}}}});
  j["steps"] = steps;
  j["polish"] = {{"vertices_moved", r.stats.polished}, {"seconds", r.stats.polishSeconds}};
  j["remesh_seconds"] = r.stats.seconds;
  j["setup_seconds"] = r.setupSeconds;
  j["provenance"] = nlohmann::json::parse(provenanceJson(r.provenance));
  return j.dump(2) + "\n";
}

}  // namespace vox::remesh
