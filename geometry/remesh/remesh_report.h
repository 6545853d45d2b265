#pragma once
// The remesher's quality report (DESIGN.md): dihedral angles, slivers,
// boundary facet angles, edge lengths against the target, and per label the
// volume change, components, Euler characteristic and the distance between
// the input and output interfaces (both one-sided distances, in mm and in
// units of the target length l); a histogram of the dihedral angles; plus the
// topology check of the labels and junctions; and the run's provenance
// (provenance.h). Printed as text and written as JSON; the histogram also
// as a PNG chart (dihedralHistogramImage).

#include "geometry/mesh_quality.h"
#include "geometry/provenance.h"
#include "geometry/remesh/interface_distance.h"
#include "geometry/remesh/mesh_topology.h"
#include "geometry/remesh/remesh.h"
#include "geometry/rgb_image.h"
#include "geometry/tet_mesh.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vox::remesh {

struct LabelReport {
  std::int32_t label = 0;
  std::string name;  // the output mesh's label name, or empty
  std::size_t tets = 0;
  double inputVolume = 0.0, outputVolume = 0.0;  // mm^3
  LabelTopology input, output;
  InterfaceDistance distance;  // zero when not measured
};

struct RemeshReport {
  double targetLength = 0.0;  // l, or l_B with a sizing field
  // The sizing field's shortest and longest target (mm); 0: uniform l.
  double sizingMin = 0.0, sizingMax = 0.0;
  std::size_t inputTets = 0;  // domain tets of the input
  std::size_t outputTets = 0, outputVertices = 0;
  TetQualitySummary quality;
  std::size_t under10 = 0;  // domain tets with a dihedral angle under 10 degrees
  // All six dihedral angles of every domain tet, in bins of one degree:
  // bin i counts the angles in [i, i + 1) degrees (180 in the last bin).
  std::array<std::size_t, 180> dihedralHistogram{};
  BoundaryFacetSummary boundaryFacets;
  EdgeLengthSummary edgeLengths;
  std::vector<LabelReport> labels;
  bool named = false;                        // labels carry names (organ table or input)
  std::vector<std::int32_t> unnamedLabels;   // when named: labels without one
  bool distancesMeasured = false;
  std::size_t junctionCurveSets = 0, junctionPointSets = 0;  // label sets with 1- / 0-junctions in the input
  std::vector<std::string> topologyDifferences;              // empty: topology preserved
  // Tagged features (feature_edges.h), when any: the output's tagged edges
  // and the one-sided Hausdorff distances (mm) between the input lines and
  // those edges (measureFeatures).
  bool featuresMeasured = false;
  std::size_t featureEdgesOut = 0;
  double featureInputToOutput = 0.0, featureOutputToInput = 0.0;
  RemeshStats stats;
  double setupSeconds = 0.0;  // reading and decomposing the input
  Provenance provenance;
};

struct ReportOptions {
  bool distances = true;               // interface Hausdorff distances (CGAL AABB trees)
  std::size_t maxDistanceSamples = 100000;
  int threads = 2;
  bool named = false;  // names were asked for (--organs): flag labels without one even when none has a name
};

// Label names are the output mesh's labelNames.
// `input` holds the domain tets the remesher started from (its volumes and
// interfaces), `inputTopology` their topology (computeGridTopology of the
// grid, or computeMeshTopology of the input mesh).
RemeshReport buildRemeshReport(const TetMesh& input, const MeshTopology& inputTopology, const TetMesh& output,
                               double targetLength, const RemeshStats& stats, const ReportOptions& options = {});

// Fills the report's feature rows from the input lines (report.stats) and
// the output's tagged edges, sampled every l / 20.
void measureFeatures(RemeshReport& report, const std::vector<FeatureSegment>& output);

std::string reportText(const RemeshReport& report);
std::string reportJson(const RemeshReport& report);

// The dihedral-angle histogram as a bar chart: one bar of 4 pixels per
// degree from 0 to 180, heights relative to the fullest bin, grid lines every
// 10 degrees (darker every 30), the ideal 70.5 degrees in green; bins under
// 15 degrees that hold any angle are drawn in red at least 4 pixels high, so
// that a single sliver shows.
RgbImage dihedralHistogramImage(const RemeshReport& report);

}  // namespace vox::remesh
