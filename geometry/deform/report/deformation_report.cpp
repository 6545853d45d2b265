#include "geometry/deform/report/deformation_report.h"

#include "geometry/skeleton/body_parts.h"
#include "geometry/skeleton/bones.h"
#include "geometry/parallel.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace vox {

namespace {

double percentChange(double before, double after) { return before > 0 ? 100.0 * (after - before) / before : 0.0; }

EdgeDistortion summarize(std::vector<double>& values) {
  EdgeDistortion d;
  d.edges = values.size();
  if (values.empty()) return d;
  double sum = 0;
  for (const double v : values) sum += v;
  d.mean = sum / double(values.size());
  // Order statistics: the same values as those of the sorted list.
  const std::size_t median = values.size() / 2, p95 = std::min(values.size() - 1, std::size_t(0.95 * double(values.size())));
  std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(p95), values.end());
  d.p95 = values[p95];
  d.max = *std::max_element(values.begin() + std::ptrdiff_t(p95), values.end());
  std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(median), values.begin() + std::ptrdiff_t(p95));
  d.median = median < p95 ? values[median] : d.p95;
  return d;
}

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

std::string changeFlag(const LabelChange& c, double flagPercent) {
  if (c.unnamed) return "unnamed";
  if (std::abs(c.volumeChangePercent) <= flagPercent) return "";
  return c.before < kSmallOrganVoxels ? "small" : "*";
}

std::string csvQuoted(const std::string& s) {
  std::string q = "\"";
  for (const char ch : s) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return q + "\"";
}

}  // namespace

std::vector<LabelChange> labelChanges(std::span<const std::uint64_t> before, std::span<const std::uint64_t> after,
                                      double voxelVolumeMm3, const OrganTable* organs) {
  std::vector<LabelChange> out;
  const std::size_t n = std::max(before.size(), after.size());
  for (std::size_t l = 1; l < n; ++l) {
    LabelChange c;
    c.label = Label(l);
    c.before = l < before.size() ? before[l] : 0;
    c.after = l < after.size() ? after[l] : 0;
    if (c.before == 0 && c.after == 0) continue;
    c.volumeChangePercent = percentChange(double(c.before), double(c.after));
    if (organs) {
      if (const Organ* o = organs->find(int(l))) c.name = o->name;
      else c.unnamed = true;
      c.massBeforeGrams = organs->mass(int(l), c.before, voxelVolumeMm3);
      c.massAfterGrams = organs->mass(int(l), c.after, voxelVolumeMm3);
    }
    out.push_back(std::move(c));
  }
  return out;
}

WholeBodyChange wholeBodyChange(std::span<const LabelChange> labels) {
  WholeBodyChange w;
  for (const LabelChange& c : labels) {
    w.before += c.before;
    w.after += c.after;
    w.massBeforeGrams += c.massBeforeGrams;
    w.massAfterGrams += c.massAfterGrams;
  }
  w.volumeChangePercent = percentChange(double(w.before), double(w.after));
  w.massChangePercent = percentChange(w.massBeforeGrams, w.massAfterGrams);
  return w;
}

OutlierDistortion outlierEdgeDistortion(const TetMesh& rest, std::span<const Eigen::Vector3d> deformed,
                                        std::span<const std::uint8_t> inside, int neighbourhoodRings) {
  // The mesh's edges (a < b) in increasing order: per vertex a, the higher
  // vertices of its tets.
  const VertexTets around = vertexTets(rest.tets, rest.vertexCount());
  std::vector<std::vector<std::int32_t>> higher(rest.vertexCount());
  parallelFor(std::int64_t(rest.vertexCount()), 0, [&](std::int64_t a) {
    std::vector<std::int32_t>& out = higher[std::size_t(a)];
    for (const std::int32_t t : around.of(std::int32_t(a)))
      for (const std::int32_t b : rest.tets[std::size_t(t)])
        if (b > a) out.push_back(b);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  });
  std::vector<std::pair<std::int32_t, std::int32_t>> edges;
  for (std::size_t a = 0; a < higher.size(); ++a)
    for (const std::int32_t b : higher[a]) edges.emplace_back(std::int32_t(a), b);

  // Rings around the outside vertices.
  const std::size_t nv = rest.vertexCount();
  std::vector<int> ring(nv, -1);
  for (std::size_t v = 0; v < nv; ++v)
    if (!inside[v]) ring[v] = 0;
  for (int r = 1; r <= neighbourhoodRings; ++r)
    for (const auto& [a, b] : edges) {
      if (ring[std::size_t(a)] == r - 1 && ring[std::size_t(b)] < 0) ring[std::size_t(b)] = r;
      if (ring[std::size_t(b)] == r - 1 && ring[std::size_t(a)] < 0) ring[std::size_t(a)] = r;
    }

  std::vector<double> outside, nearby, all;
  for (const auto& [a, b] : edges) {
    const double restLength = (rest.positions[std::size_t(a)] - rest.positions[std::size_t(b)]).norm();
    const double length = (deformed[std::size_t(a)] - deformed[std::size_t(b)]).norm();
    if (!(restLength > 0)) continue;
    const double d = std::abs(std::log(length / restLength));
    if (!inside[std::size_t(a)] || !inside[std::size_t(b)]) {
      outside.push_back(d);
      continue;
    }
    all.push_back(d);
    if (ring[std::size_t(a)] >= 0 && ring[std::size_t(b)] >= 0) nearby.push_back(d);
  }
  return {summarize(outside), summarize(nearby), summarize(all)};
}

void describePipeline(DeformationReport& report, const DeformationPipeline& pipeline) {
  const PipelineStats& s = pipeline.stats();
  report.automaticCage = s.automaticCage;
  report.selections.clear();
  for (const PoseSelection& sel : pipeline.pose().selections) report.selections.emplace_back(sel.name, 0);
  for (const std::int32_t k : pipeline.handles().selection) ++report.selections[std::size_t(k)].second;
  report.cageVertices = pipeline.cage().vertexCount();
  report.cageFaces = pipeline.cage().faceCount();
  report.cage = s.cage;
  report.foregroundOutsideCage = s.foregroundOutsideCage;
  report.envelopeVertices = pipeline.envelope().vertexCount();
  report.envelopeFaces = pipeline.envelope().faceCount();
  report.envelopeOutside = pipeline.deformer().stats().envelopeOutside;
  const TetMesh& tm = pipeline.transferMesh();
  report.tmInside = std::size_t(std::count(pipeline.transferMeshInside().begin(), pipeline.transferMeshInside().end(), 1));
  report.tmOutside = tm.vertexCount() - report.tmInside;
  report.uncoveredVoxels = s.uncoveredVoxels;
  report.cuts = s.cuts;
  const auto& deformed = pipeline.deformedTransferMesh();
  report.outlierDistortion = outlierEdgeDistortion(tm, deformed, pipeline.transferMeshInside());
  const RigidBoneGroups& rigid = pipeline.rigidBones();
  report.rigidGroups = pipeline.deformer().stats().rigidGroups;
  report.rigidVertices = pipeline.deformer().stats().rigidVertices;
  report.sharedBoneVertices = rigid.sharedVertices;
  report.uncoveredBoneVoxels = rigid.uncoveredVoxels;
  report.bones = measureBoneRigidity(rigid, tm, deformed);
  describeTransferMesh(report, tm, deformed);
}

void describeTransferMesh(DeformationReport& report, const TetMesh& tm, const std::vector<Eigen::Vector3d>& deformed) {
  report.tmVertices = tm.vertexCount();
  report.tmTets = tm.tetCount();
  report.distortion = distortionHistograms(tm, deformed);
  report.tmInverted = 0;
  double inverted = 0.0, total = 0.0;
  for (const Tet& t : tm.tets) {
    const double rest = signedVolume(tm.positions, t);
    total += rest;
    if (!(signedVolume(deformed, t) > 0.0)) {
      ++report.tmInverted;
      inverted += rest;
    }
  }
  report.tmInvertedVolumeFraction = total > 0.0 ? inverted / total : 0.0;
}

std::string deformationSummary(const DeformationReport& r) {
  std::ostringstream s;
  double wall = 0, cpu = 0;
  for (const StageTime& t : r.stages) {
    wall += t.seconds;
    cpu += t.cpuSeconds;
  }
  s << r.output << ": " << r.posed.dims[0] << " x " << r.posed.dims[1] << " x " << r.posed.dims[2] << " voxels";
  if (r.samples > 1) s << ", " << r.samples << "^3 samples per voxel";
  s << ", " << r.engine << ", " << fixed(wall, 1) << " s (" << fixed(cpu, 1) << " CPU s)\n";
  s << "  stages:";
  for (const StageTime& t : r.stages) s << " " << t.name << " " << fixed(t.seconds, 1) << " s;";
  s << "\n";
  s << "  cage " << r.cageVertices << " vertices (" << (r.automaticCage ? "automatic" : "from file") << "), envelope "
    << r.envelopeVertices << " vertices, transfer mesh " << r.tmVertices << " vertices / " << r.tmTets << " tets";
  if (r.workingFactor > 1) s << " (working grid downsampled by " << r.workingFactor << ")";
  s << "\n  handles:";
  for (const auto& [name, vertices] : r.selections) s << " " << name << " " << vertices << ";";
  s << "\n";
  s << "  outliers: " << r.tmOutside << " TM vertices and " << r.foregroundOutsideCage << " foreground voxels outside the cage; "
    << r.tmInverted << " TM tets inverted by the deformation\n";
  if (!r.refinement.steps.empty()) {
    s << "  refinement (" << r.refinement.stopReason << "):";
    for (const RefinementStep& st : r.refinement.steps)
      s << " " << st.tets << " tets max/mean error " << fixed(st.maxError, 4) << "/" << fixed(st.meanError, 4) << ";";
    s << "\n";
  }
  s << "  whole body: " << r.wholeBody.before << " -> " << r.wholeBody.after << " voxels (" << fixed(r.wholeBody.volumeChangePercent, 2)
    << " % volume";
  if (r.withMasses) s << ", " << fixed(r.wholeBody.massChangePercent, 2) << " % mass";
  s << ")\n";
  const auto areas = [](const BodyProjection& p) {
    return fixed(p.frontMm2 * 1e-6, 4) + " / " + fixed(p.sideMm2 * 1e-6, 4) + " / " + fixed(p.topMm2 * 1e-6, 4) + " m^2, height " +
           fixed(p.heightMm, 1) + " mm";
  };
  s << "  projected area front / side / top: " << areas(r.restProjection) << " at rest -> " << areas(r.posedProjection) << " posed\n";
  const LabelChange* worst = nullptr;
  std::size_t small = 0;
  for (const LabelChange& c : r.labels) {
    if (c.before < kSmallOrganVoxels) {
      ++small;
      continue;
    }
    if (!worst || std::abs(c.volumeChangePercent) > std::abs(worst->volumeChangePercent)) worst = &c;
  }
  if (worst)
    s << "  largest change of a label with >= " << kSmallOrganVoxels << " voxels: " << worst->label
      << (worst->name.empty() ? "" : " (" + worst->name + ")") << " " << fixed(worst->volumeChangePercent, 2) << " %; " << small
      << " labels under " << kSmallOrganVoxels << " voxels\n";
  if (const auto& c = r.volumeCorrection)
    s << "  volume correction: " << c->relabelled << " of " << c->candidates << " boundary voxels relabelled (" << c->still
      << " where the deformation did not move the tissue kept); largest gap "
      << "between a label's voxels and its " << (c->toRestVolumes ? "rest" : "deformed") << " volume "
      << fixed(c->worstPercentBefore, 2) << " % -> "
      << fixed(c->worstPercentAfter, 2) << " %\n";
  if (const auto& c = r.skinCover; c && c->bareVoxels > 0)
    s << "  skin cover: " << c->covered << " voxels of tissue the pose bared relabelled skin, " << c->overBone
      << " laid over " << c->boneVoxels << " voxels of bared bone; " << c->bareAtRest << " bare at rest too left as they are\n";
  if (!r.bones.empty()) {
    const BoneRigidity* strained = nullptr;
    const BoneRigidity* changed = nullptr;
    for (const BoneRigidity& b : r.bones) {
      if (!strained || b.maxStrain > strained->maxStrain) strained = &b;
      if (!changed || std::abs(b.volumeChangePercent()) > std::abs(changed->volumeChangePercent())) changed = &b;
    }
    const auto name = [](const BoneRigidity& b) {
      return std::string(skeleton::boneName(skeleton::Bone(b.key % kBoneKeyStride))) + " of the " +
             skeleton::partName(skeleton::Part(b.key / kBoneKeyStride));
    };
    if (r.rigidGroups > 0)
      s << "  rigid bones: " << r.rigidGroups << " parts, " << r.rigidVertices << " TM vertices held rigid, " << r.sharedBoneVertices
        << " between two parts' bones left free";
    else
      s << "  bones (not held rigid)";
    if (strained)
      s << "; largest |ln(l'/l)| over a bone's TM edges " << fixed(strained->maxStrain, 4) << " (" << name(*strained)
        << "), largest bone volume change " << fixed(changed->volumeChangePercent(), 2) << " % (" << name(*changed) << ")";
    s << "\n";
  }
  if (const auto& c = r.collisions) {
    s << "  collisions: " << c->voxels << " voxels (" << fixed(c->volumeMm3() * 1e-3, 2) << " mL, " << fixed(100.0 * c->bodyFraction(), 3)
      << " % of the body) hold tissue of two body parts";
    for (std::size_t k = 0; k < c->pairs.size() && k < 3; ++k)
      s << (k ? ", " : ": ") << skeleton::partName(skeleton::Part(c->pairs[k].partA)) << " / "
        << skeleton::partName(skeleton::Part(c->pairs[k].partB)) << " " << c->pairs[k].voxels;
    s << "\n";
    double area = 0.0;
    for (const ContactPair& p : c->contacts) area += p.areaMm2;
    s << "  contacts: " << fixed(area * 1e-2, 1) << " cm2 where tissue of two body parts apart at rest meets";
    for (std::size_t k = 0; k < c->contacts.size() && k < 3; ++k)
      s << (k ? ", " : ": ") << skeleton::partName(skeleton::Part(c->contacts[k].partA)) << " / "
        << skeleton::partName(skeleton::Part(c->contacts[k].partB)) << " " << fixed(c->contacts[k].areaMm2 * 1e-2, 1);
    s << "\n";
  }
  s << "  distortion: angle mean " << fixed(r.distortion.angle.mean, 2) << " deg (rms deviation " << fixed(r.distortion.angle.rmsDeviation, 2)
    << "), stretch mean " << fixed(r.distortion.stretch.mean, 4) << " (rms deviation " << fixed(r.distortion.stretch.rmsDeviation, 4) << ")\n";
  return s.str();
}

std::string labelChangeTable(const DeformationReport& r, double flagPercent) {
  std::ostringstream s;
  char line[256];
  if (r.withMasses)
    std::snprintf(line, sizeof line, "%6s  %-36s %10s %10s %11s %11s %8s  %s\n", "label", "organ", "voxels", "after", "mass g",
                  "after g", "change %", "flag");
  else
    std::snprintf(line, sizeof line, "%6s  %-36s %10s %10s %8s  %s\n", "label", "organ", "voxels", "after", "change %", "flag");
  s << line;
  for (const LabelChange& c : r.labels) {
    const std::string name = c.unnamed ? "(not in organ table)" : c.name;
    const std::string flag = changeFlag(c, flagPercent);
    if (r.withMasses)
      std::snprintf(line, sizeof line, "%6d  %-36.36s %10llu %10llu %11.3f %11.3f %+8.2f  %s\n", int(c.label), name.c_str(),
                    (unsigned long long)c.before, (unsigned long long)c.after, c.massBeforeGrams, c.massAfterGrams,
                    c.volumeChangePercent, flag.c_str());
    else
      std::snprintf(line, sizeof line, "%6d  %-36.36s %10llu %10llu %+8.2f  %s\n", int(c.label), name.c_str(),
                    (unsigned long long)c.before, (unsigned long long)c.after, c.volumeChangePercent, flag.c_str());
    std::string row(line);
    while (row.size() > 1 && row[row.size() - 2] == ' ') row.erase(row.size() - 2, 1);
    s << row;
  }
  std::size_t flagged = 0;
  for (const LabelChange& c : r.labels) flagged += changeFlag(c, flagPercent) == "*";
  s << "  " << flagged << " organs of " << kSmallOrganVoxels << " voxels or more changed by more than " << fixed(flagPercent, 1)
    << " % (*); small: the same under " << kSmallOrganVoxels << " voxels\n";
  return s.str();
}

std::string labelChangeCsv(const DeformationReport& r, double flagPercent) {
  std::ostringstream s;
  s << "label,name,voxels_before,voxels_after,volume_before_mm3,volume_after_mm3,mass_before_g,mass_after_g,change_pct,flag\n";
  const double vv = r.source.voxelVolume();
  for (const LabelChange& c : r.labels) {
    s << c.label << "," << csvQuoted(c.name) << "," << c.before << "," << c.after << "," << fixed(double(c.before) * vv, 3) << ","
      << fixed(double(c.after) * vv, 3) << ",";
    if (r.withMasses && !c.unnamed) s << fixed(c.massBeforeGrams, 4) << "," << fixed(c.massAfterGrams, 4);
    else s << ",";
    s << "," << fixed(c.volumeChangePercent, 4) << "," << changeFlag(c, flagPercent) << "\n";
  }
  return s.str();
}

std::vector<std::string> deformationWarnings(const DeformationReport& r) {
  std::vector<std::string> w;
  if (r.tmInverted > 0)
    w.push_back(std::to_string(r.tmInverted) + " transfer-mesh tets inverted by the deformation (" +
                fixed(100.0 * r.tmInvertedVolumeFraction, 3) +
                " % of the volume): the map folds there and the posed grid takes one side of the fold");
  const DistortionHistogram& st = r.distortion.stretch;
  const DistortionHistogram& an = r.distortion.angle;
  if (st.max >= kLargeStretch || (st.min > 0 && st.min <= 1.0 / kLargeStretch))
    w.push_back("large distortion: dual edges stretched up to " + fixed(st.max, 2) + "x and shrunk down to " + fixed(st.min, 2) +
                "x (" + fixed(100.0 * (st.above + st.below), 2) + " % of the volume outside 0.5x-1.5x)");
  if (std::max(an.max - 90.0, 90.0 - an.min) >= kLargeAngleDeviationDeg)
    w.push_back("large distortion: right angles sheared to " + fixed(an.min, 1) + "-" + fixed(an.max, 1) + " degrees");
  if (r.rigidBonesRequested && r.rigidGroups == 0)
    w.push_back(r.bones.empty() ? "--rigid-bones: no bones to hold rigid (a joint pose or --parts gives the body parts)"
                                : "--rigid-bones: no bone could be held rigid: every transfer-mesh vertex at a bone lies near another part's bone "
                                  "(a transfer mesh too coarse for the skeleton)");
  if (r.volumeCorrection && r.volumeCorrection->gapsFilled > 0)
    w.push_back(std::to_string(r.volumeCorrection->gapsFilled) +
                " voxels of gaps inside the body (surfaces the pose parted, covered by no tet) filled with the tissue around them");
  if (const auto& c = r.skinCover) {
    // The skin the cover added, against each skin label's rest voxels.
    const LabelChange* most = nullptr;
    double mostPercent = 0.0;
    for (const LabelChange& l : r.labels)
      if (l.label < c->to.size() && c->to[l.label] > 0 && l.before > 0) {
        const double percent = 100.0 * double(c->to[l.label]) / double(l.before);
        if (!most || percent > mostPercent) most = &l, mostPercent = percent;
      }
    if (most && mostPercent > kSkinCoverWarnPercent)
      w.push_back("the skin cover added " + std::to_string(c->to[most->label]) + " voxels to " +
                  (most->name.empty() ? "label " + std::to_string(most->label) : most->name) + " (" + fixed(mostPercent, 1) +
                  " % of its rest voxels): where a limb turns its surface across slices thicker than the skin, the skin there is a "
                  "voxel thick; --no-skin-cover leaves that tissue bare");
  }
  std::string unnamed;
  std::size_t count = 0;
  for (const LabelChange& c : r.labels)
    if (c.unnamed) {
      unnamed += (count++ ? ", " : " ") + std::to_string(c.label) + " (" + std::to_string(c.before) + " voxels)";
    }
  if (count > 0) w.push_back("labels without a name in the organ table:" + unnamed + "; their mass is left out of the totals");
  return w;
}

}  // namespace vox
