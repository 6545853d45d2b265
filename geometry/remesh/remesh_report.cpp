#include "geometry/remesh/remesh_report.h"

#include "geometry/cancellation.h"
#include "geometry/progress.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace vox::remesh {

namespace {

void histogramDihedralAngles(const TetMesh& mesh, RemeshReport& r) {
  const auto& P = mesh.positions;
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    if (t % 65536 == 0) throwIfCancelled();
    if (mesh.labels[t] <= 0) continue;
    const Tet& q = mesh.tets[t];
    const auto angles = dihedralAngles(P[std::size_t(q[0])], P[std::size_t(q[1])], P[std::size_t(q[2])], P[std::size_t(q[3])]);
    double lo = 180.0;
    for (double a : angles) {
      lo = std::min(lo, a);
      ++r.dihedralHistogram[std::size_t(std::clamp(int(std::floor(a)), 0, 179))];
    }
    r.under10 += lo < 10.0;
  }
}

}  // namespace

RemeshReport buildRemeshReport(const TetMesh& input, const MeshTopology& inputTopology, const TetMesh& output,
                               double targetLength, const RemeshStats& stats, const ReportOptions& options) {
  reportProgress("quality report", 0.0);
  RemeshReport r;
  r.targetLength = targetLength;
  r.stats = stats;
  for (std::int32_t l : input.labels) r.inputTets += l > 0;
  r.outputVertices = output.vertexCount();
  r.quality = summarizeTetQuality(output);
  histogramDihedralAngles(output, r);
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
  if (r.sizingMax > 0.0) add("sizing field         adaptive, l from %.4g to %.4g mm\n", r.sizingMin, r.sizingMax);
  add("tets                 %zu (input %zu), %zu vertices\n", r.outputTets, r.inputTets, r.outputVertices);
  add("dihedral angles      min %.2f, max %.2f degrees; mean |angle - 70.5| %.2f\n", r.quality.minDihedral,
      r.quality.maxDihedral, r.quality.meanDeviationFrom70);
  add("slivers              %zu tets under 15 degrees, %zu under 10, %zu under 5; %zu inverted\n", r.quality.under15,
      r.under10, r.quality.under5, r.quality.inverted);
  add("boundary facets      %zu, angles %.2f to %.2f degrees, mean |angle - 60| %.2f\n", r.boundaryFacets.facets,
      r.boundaryFacets.minAngle, r.boundaryFacets.maxAngle, r.boundaryFacets.meanDeviationFrom60);
  add("edge lengths         %.3g to %.3g mm, mean %.3g, mean |length - l| / l %.1f%%\n", r.edgeLengths.minLength,
      r.edgeLengths.maxLength, r.edgeLengths.meanLength, 100.0 * r.edgeLengths.meanRelativeDeviation);
  double worstVolume = 0.0, worstOut = 0.0, worstIn = 0.0, inTotal = 0.0, outTotal = 0.0;
  std::int32_t worstVolumeLabel = 0, worstOutLabel = 0, worstInLabel = 0;
  for (const LabelReport& l : r.labels) {
    const double c = std::abs(relativeChange(l.inputVolume, l.outputVolume));
    if (c > worstVolume) worstVolume = c, worstVolumeLabel = l.label;
    if (l.distance.outputToInput > worstOut) worstOut = l.distance.outputToInput, worstOutLabel = l.label;
    if (l.distance.inputToOutput > worstIn) worstIn = l.distance.inputToOutput, worstInLabel = l.label;
    inTotal += l.inputVolume;
    outTotal += l.outputVolume;
  }
  add("volume               total change %+.2f%%, largest label change %.2f%% (label %d)\n",
      100.0 * relativeChange(inTotal, outTotal), 100.0 * worstVolume, worstVolumeLabel);
  if (r.distancesMeasured) {
    const double l = r.targetLength;
    add("interface distance   largest sampled Hausdorff %.3g mm = %.3g l (output to input %.3g l, label %d; input to "
        "output %.3g l, label %d)\n",
        std::max(worstOut, worstIn), std::max(worstOut, worstIn) / l, worstOut / l, worstOutLabel, worstIn / l, worstInLabel);
  }
  if (r.featuresMeasured) {
    const double l = r.targetLength;
    add("features             %zu lines, %zu tagged edges in, %zu out; Hausdorff input to output %.3g l, output to "
        "input %.3g l\n",
        r.stats.featureLines, r.stats.featureEdges, r.featureEdgesOut, r.featureInputToOutput / l,
        r.featureOutputToInput / l);
  }
  add("topology             %s: %zu labels, 1-junctions of %zu label sets, 0-junctions of %zu label sets\n",
      r.topologyDifferences.empty() ? "preserved" : "CHANGED", r.labels.size(), r.junctionCurveSets, r.junctionPointSets);
  for (std::size_t i = 0; i < r.topologyDifferences.size() && i < 20; ++i) s += "  " + r.topologyDifferences[i] + "\n";
  add("time                 %.2f s remeshing (%.2f s reading and preparing the input; polish %zu vertices, %.2f s; "
      "%zu Steiner points and %zu flips, %.2f s)\n",
      r.stats.seconds, r.setupSeconds, r.stats.polished, r.stats.polishSeconds, r.stats.inserted, r.stats.sliverFlips,
      r.stats.insertSeconds);
  if (!r.unnamedLabels.empty()) {
    s += "unnamed labels      ";
    for (std::size_t i = 0; i < r.unnamedLabels.size(); ++i) s += (i ? ", " : " ") + std::to_string(r.unnamedLabels[i]);
    s += " (no name in the organ table)\n";
  }
  std::size_t nameWidth = r.named ? 9 : 0;  // at least "(unnamed)"
  if (r.named)
    for (const LabelReport& l : r.labels) nameWidth = std::max(nameWidth, std::min<std::size_t>(l.name.size(), 32));
  s += "label  " + (nameWidth ? (std::string("name") + std::string(nameWidth > 4 ? nameWidth - 4 : 0, ' ') + "  ") : std::string()) +
       "      tets   volume in -> out (mm^3)    change  comps  euler  out->in in->out (l)\n";
  for (const LabelReport& l : r.labels) {
    add("%5d  ", l.label);
    if (nameWidth) add("%-*.*s  ", int(nameWidth), int(nameWidth), l.name.empty() ? "(unnamed)" : l.name.c_str());
    add("%10zu  %12.1f -> %12.1f  %+7.2f%%  %2zu/%-2zu  %3lld/%-3lld", l.tets, l.inputVolume, l.outputVolume,
        100.0 * relativeChange(l.inputVolume, l.outputVolume), l.input.components, l.output.components,
        (long long)l.input.euler, (long long)l.output.euler);
    if (r.distancesMeasured)
      add("  %7.3f %7.3f", l.distance.outputToInput / r.targetLength, l.distance.inputToOutput / r.targetLength);
    s += "\n";
  }
  return s;
}

void measureFeatures(RemeshReport& r, const std::vector<FeatureSegment>& output) {
  r.featuresMeasured = true;
  r.featureEdgesOut = output.size();
  const double step = r.targetLength / 20.0;
  r.featureInputToOutput = oneSidedLineDistance(r.stats.featureInput, output, step);
  r.featureOutputToInput = oneSidedLineDistance(output, r.stats.featureInput, step);
}

std::string reportJson(const RemeshReport& r) {
  nlohmann::json j;
  j["target_edge_length_mm"] = r.targetLength;
  if (r.sizingMax > 0.0) j["sizing_field_mm"] = {{"min", r.sizingMin}, {"max", r.sizingMax}};
  j["tets"] = {{"input", r.inputTets}, {"output", r.outputTets}};
  if (r.featuresMeasured)
    j["features"] = {{"lines", r.stats.featureLines},
                     {"edges_in", r.stats.featureEdges},
                     {"edges_out", r.featureEdgesOut},
                     {"hausdorff_mm", {{"input_to_output", r.featureInputToOutput}, {"output_to_input", r.featureOutputToInput}}},
                     {"hausdorff_over_l",
                      {{"input_to_output", r.featureInputToOutput / r.targetLength},
                       {"output_to_input", r.featureOutputToInput / r.targetLength}}}};
  j["vertices"] = r.outputVertices;
  j["dihedral_degrees"] = {{"min", r.quality.minDihedral},
                           {"max", r.quality.maxDihedral},
                           {"mean_deviation_from_70_5", r.quality.meanDeviationFrom70}};
  j["tets_under_15_degrees"] = r.quality.under15;
  j["tets_under_10_degrees"] = r.under10;
  j["tets_under_5_degrees"] = r.quality.under5;
  j["dihedral_histogram"] = {{"bin_degrees", 1}, {"counts", r.dihedralHistogram}};
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
                            "each label's boundary facets to the other mesh's, both ways; CGAL AABB tree; "
                            "interface_distance_over_l divides by the target edge length"
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
    if (r.distancesMeasured)
      e["interface_distance_over_l"] = {{"output_to_input", l.distance.outputToInput / r.targetLength},
                                        {"input_to_output", l.distance.inputToOutput / r.targetLength},
                                        {"hausdorff", l.distance.hausdorff() / r.targetLength}};
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
  j["steiner_points"] = {{"inserted", r.stats.inserted}, {"flips_after", r.stats.sliverFlips}, {"seconds", r.stats.insertSeconds}};
  j["remesh_seconds"] = r.stats.seconds;
  j["setup_seconds"] = r.setupSeconds;
  j["provenance"] = nlohmann::json::parse(provenanceJson(r.provenance));
  return j.dump(2) + "\n";
}

RgbImage dihedralHistogramImage(const RemeshReport& report) {
  constexpr int kBar = 4, kMargin = 8, kPlot = 200;
  const Rgb background{255, 255, 255}, grid{225, 225, 225}, grid30{170, 170, 170}, bar{60, 90, 160},
      sliver{210, 40, 40}, ideal{40, 160, 60};
  RgbImage image(180 * kBar + 2 * kMargin, kPlot + 2 * kMargin, background);
  const int base = kMargin + kPlot;  // the row below the plot
  auto column = [&](int x, int from, int to, Rgb c) {
    for (int y = from; y < to; ++y) image.at(x, y) = c;
  };
  for (int d = 0; d <= 180; d += 10) column(kMargin + d * kBar - (d == 180), kMargin, base, d % 30 ? grid : grid30);
  const std::size_t fullest = *std::max_element(report.dihedralHistogram.begin(), report.dihedralHistogram.end());
  for (int i = 0; i < 180; ++i) {
    const std::size_t n = report.dihedralHistogram[std::size_t(i)];
    if (n == 0) continue;
    int h = int(std::lround(double(kPlot) * double(n) / double(fullest)));
    if (i < 15) h = std::max(h, 4);
    h = std::max(h, 1);
    for (int x = 0; x < kBar - 1; ++x) column(kMargin + i * kBar + x, base - h, base, i < 15 ? sliver : bar);
  }
  column(kMargin + int(std::lround(std::acos(1.0 / 3.0) * 180.0 / M_PI * kBar)), kMargin, base, ideal);
  for (int x = kMargin; x < kMargin + 180 * kBar; ++x) image.at(x, base) = grid30;
  return image;
}

}  // namespace vox::remesh
