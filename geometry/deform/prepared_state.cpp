#include "geometry/deform/prepared_state.h"

#include "geometry/ascii_text.h"
#include "geometry/atomic_file.h"
#include "geometry/error.h"
#include "geometry/io/input_provenance.h"
#include "geometry/io/section_file.h"
#include "geometry/sha256.h"
#include "geometry/skeleton/label_groups.h"
#include "geometry/world_frame.h"

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <cstring>

namespace vox {

namespace {

constexpr SectionFileKind kKind{"VXPREP\r\n", kPreparedStateVersion, "voxmorph prepared state", "voxmorph prepare"};

// ---- keys -------------------------------------------------------------

// Two 64-bit lanes of a multiply-xorshift hash over 8-byte words.
class FastHash {
public:
  void update(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8) {
      std::uint64_t w;
      std::memcpy(&w, p + i, 8);
      mix(w);
    }
    std::uint64_t tail = 0;
    if (i < n) {
      std::memcpy(&tail, p + i, n - i);
      mix(tail ^ (std::uint64_t(n - i) << 56));
    }
    length_ += n;
  }
  std::string hex() {
    mix(length_);
    char s[33];
    std::snprintf(s, sizeof s, "%016" PRIx64 "%016" PRIx64, finish(a_), finish(b_));
    return s;
  }

private:
  void mix(std::uint64_t w) {
    a_ = (a_ ^ w) * 0x9e3779b97f4a7c15ULL;
    a_ ^= a_ >> 32;
    b_ = (b_ + w) * 0xc2b2ae3d27d4eb4fULL;
    b_ ^= b_ >> 29;
    b_ = b_ * 0x165667b19e3779f9ULL + a_;
  }
  static std::uint64_t finish(std::uint64_t h) {
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    h ^= h >> 33;
    return h;
  }
  std::uint64_t a_ = 0x243f6a8885a308d3ULL, b_ = 0x13198a2e03707344ULL, length_ = 0;
};

void hashGeometry(FastHash& h, const GridGeometry& g) {
  h.update(g.dims.data(), sizeof(g.dims));
  h.update(g.spacing.data(), 3 * sizeof(double));
  h.update(g.origin.data(), 3 * sizeof(double));
  h.update(g.direction.data(), 9 * sizeof(double));
}

std::string exact(double v) {
  char s[64];
  std::snprintf(s, sizeof s, "%a", v);
  return s;
}

std::string groupName(Label g) {
  return g >= 1 && g <= kLabelGroupCount ? labelGroupName(LabelGroup(g)) : "group " + std::to_string(g);
}

// ---- packing ------------------------------------------------------------

void putPoints(SectionPacker& p, const std::vector<Eigen::Vector3d>& points) {
  std::vector<double> flat(points.size() * 3);
  for (std::size_t i = 0; i < points.size(); ++i)
    for (int a = 0; a < 3; ++a) flat[3 * i + std::size_t(a)] = points[i][a];
  p.putVector(flat);
}

std::vector<Eigen::Vector3d> getPoints(SectionUnpacker& u) {
  const std::vector<double> flat = u.getVector<double>();
  if (flat.size() % 3 != 0) u.invalid("a point list of " + std::to_string(flat.size()) + " coordinates");
  std::vector<Eigen::Vector3d> points(flat.size() / 3);
  for (std::size_t i = 0; i < points.size(); ++i) points[i] = {flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]};
  return points;
}

void putVector3(SectionPacker& p, const Eigen::Vector3d& v) {
  for (int a = 0; a < 3; ++a) p.put(v[a]);
}

Eigen::Vector3d getVector3(SectionUnpacker& u) {
  Eigen::Vector3d v;
  for (int a = 0; a < 3; ++a) v[a] = u.get<double>();
  return v;
}

void putGeometry(SectionPacker& p, const GridGeometry& g) {
  for (const std::int64_t d : g.dims) p.put(d);
  putVector3(p, g.spacing);
  putVector3(p, g.origin);
  for (int i = 0; i < 9; ++i) p.put(g.direction.data()[i]);
}

GridGeometry getGeometry(SectionUnpacker& u, const std::string& source) {
  GridGeometry g;
  for (std::int64_t& d : g.dims) d = u.get<std::int64_t>();
  g.spacing = getVector3(u);
  g.origin = getVector3(u);
  for (int i = 0; i < 9; ++i) g.direction.data()[i] = u.get<double>();
  g.validate(source);
  return g;
}

void putTriMesh(SectionPacker& p, const TriMesh& m) {
  putPoints(p, m.positions);
  p.putVector(m.triangles);
}

TriMesh getTriMesh(SectionUnpacker& u, const std::string& source) {
  TriMesh m;
  m.positions = getPoints(u);
  m.triangles = u.getVector<Tri>();
  m.validate(source);
  return m;
}

void putTetMesh(SectionPacker& p, const TetMesh& m) {
  putPoints(p, m.positions);
  p.putVector(m.tets);
  p.putVector(m.labels);
  p.put(std::uint64_t(m.labelNames.size()));
  for (const auto& [label, name] : m.labelNames) {
    p.put(label);
    p.putString(name);
  }
}

TetMesh getTetMesh(SectionUnpacker& u, const std::string& source) {
  TetMesh m;
  m.positions = getPoints(u);
  m.tets = u.getVector<Tet>();
  m.labels = u.getVector<std::int32_t>();
  const std::size_t names = u.getCount(4 + 8);
  for (std::size_t i = 0; i < names; ++i) {
    const auto label = u.get<std::int32_t>();
    m.labelNames[label] = u.getString();
  }
  m.validate(source);
  return m;
}

void putCutReport(SectionPacker& p, const CutReport& c) {
  for (const std::size_t n : {c.cutFaces, c.duplicatedVertices, c.openedRimFaces, c.contactVertices}) p.put(std::uint64_t(n));
  p.putVector(c.splitVertices);
}

CutReport getCutReport(SectionUnpacker& u, std::size_t vertexCount) {
  CutReport c;
  for (std::size_t* n : {&c.cutFaces, &c.duplicatedVertices, &c.openedRimFaces, &c.contactVertices}) *n = std::size_t(u.get<std::uint64_t>());
  c.splitVertices = u.getVector<std::int32_t>();
  for (const std::int32_t v : c.splitVertices)
    if (v < 0 || std::size_t(v) >= vertexCount) u.invalid("split vertex " + std::to_string(v) + " outside the mesh");
  return c;
}

void putArticulatedMesh(SectionPacker& p, const ArticulatedMesh& m) {
  putTetMesh(p, m.mesh);
  p.put(std::uint64_t(m.bodies.size()));
  for (const ArticularBody& b : m.bodies) {
    for (const std::uint8_t e : {std::uint8_t(b.joint), std::uint8_t(b.shape), std::uint8_t(b.owner), std::uint8_t(b.other)}) p.put(e);
    for (const Eigen::Vector3d* v : {&b.centre, &b.axis, &b.attachment}) putVector3(p, *v);
    for (const double v : {b.radius, b.halfLength, b.attachmentHalfAngleDeg}) p.put(v);
  }
  p.put(std::uint64_t(m.cuts.size()));
  for (const CutReport& c : m.cuts) putCutReport(p, c);
  putCutReport(p, m.limbCut);
  putCutReport(p, m.boneGapCut);
  std::vector<std::uint8_t> role(m.role.size()), part(m.vertexPart.size());
  for (std::size_t v = 0; v < role.size(); ++v) role[v] = std::uint8_t(m.role[v]);
  for (std::size_t v = 0; v < part.size(); ++v) part[v] = std::uint8_t(m.vertexPart[v]);
  p.putVector(role);
  p.putVector(part);
  p.putVector(m.vertexBody);
  for (const std::size_t n : {m.conflictVertices, m.resolvedBoneVoxels, m.snappedVertices, m.unsnappedVertices, m.splitEdges, m.cutOffTissueVertices})
    p.put(std::uint64_t(n));
  for (const std::size_t n : m.rigidVertices) p.put(std::uint64_t(n));
  p.put(std::uint64_t(m.bodySurfaces.size()));
  for (const auto& surface : m.bodySurfaces) {
    std::vector<Eigen::Vector3d> corners;
    for (const auto& triangle : surface) corners.insert(corners.end(), triangle.begin(), triangle.end());
    putPoints(p, corners);
  }
  p.put(m.seconds);
}

ArticulatedMesh getArticulatedMesh(SectionUnpacker& u, const std::string& source) {
  ArticulatedMesh m;
  m.mesh = getTetMesh(u, source);
  const std::size_t nv = m.mesh.vertexCount();
  const std::size_t bodies = u.getCount(4 + 9 * 8 + 3 * 8);
  for (std::size_t i = 0; i < bodies; ++i) {
    ArticularBody b;
    const auto joint = u.get<std::uint8_t>(), shape = u.get<std::uint8_t>(), owner = u.get<std::uint8_t>(), other = u.get<std::uint8_t>();
    if (joint >= skeleton::kJointCount || shape > std::uint8_t(ArticularShape::Cylinder) || owner > kSegmentCount ||
        other > kSegmentCount)
      u.invalid("articular body " + std::to_string(i) + ": joint, shape or part out of range");
    b.joint = skeleton::JointId(joint);
    b.shape = ArticularShape(shape);
    b.owner = skeleton::Part(owner);
    b.other = skeleton::Part(other);
    for (Eigen::Vector3d* v : {&b.centre, &b.axis, &b.attachment}) *v = getVector3(u);
    for (double* v : {&b.radius, &b.halfLength, &b.attachmentHalfAngleDeg}) *v = u.get<double>();
    m.bodies.push_back(b);
  }
  const std::size_t cuts = u.getCount(4 * 8 + 8);
  for (std::size_t i = 0; i < cuts; ++i) m.cuts.push_back(getCutReport(u, nv));
  m.limbCut = getCutReport(u, nv);
  m.boneGapCut = getCutReport(u, nv);
  const std::vector<std::uint8_t> role = u.getVector<std::uint8_t>(), part = u.getVector<std::uint8_t>();
  m.vertexBody = u.getVector<std::int8_t>();
  if (role.size() != nv || part.size() != nv || m.vertexBody.size() != nv) u.invalid("per-vertex arrays of another length than the mesh's");
  for (std::size_t v = 0; v < nv; ++v) {
    if (role[v] > std::uint8_t(VertexRole::Sliding) || part[v] > kSegmentCount ||
        m.vertexBody[v] < -1 || m.vertexBody[v] >= std::int64_t(m.bodies.size()))
      u.invalid("vertex " + std::to_string(v) + ": role, part or body out of range");
    m.role.push_back(VertexRole(role[v]));
    m.vertexPart.push_back(skeleton::Part(part[v]));
  }
  for (std::size_t* n : {&m.conflictVertices, &m.resolvedBoneVoxels, &m.snappedVertices, &m.unsnappedVertices, &m.splitEdges, &m.cutOffTissueVertices})
    *n = std::size_t(u.get<std::uint64_t>());
  for (std::size_t& n : m.rigidVertices) n = std::size_t(u.get<std::uint64_t>());
  const std::size_t surfaces = u.getCount(8);
  if (surfaces != m.bodies.size()) u.invalid("body surfaces of another count than the bodies'");
  for (std::size_t i = 0; i < surfaces; ++i) {
    const std::vector<Eigen::Vector3d> corners = getPoints(u);
    if (corners.size() % 3 != 0) u.invalid("a body surface's corners are not triangles");
    std::vector<std::array<Eigen::Vector3d, 3>> surface(corners.size() / 3);
    for (std::size_t t = 0; t < surface.size(); ++t) surface[t] = {corners[3 * t], corners[3 * t + 1], corners[3 * t + 2]};
    m.bodySurfaces.push_back(std::move(surface));
  }
  m.seconds = u.get<double>();
  return m;
}

void putSurfaceCheck(SectionPacker& p, const SurfaceCheck& c) {
  for (const std::size_t n : {c.vertices, c.edges, c.faces, c.boundaryEdges, c.nonManifoldEdges, c.nonManifoldVertices, c.misorientedEdges,
                              c.isolatedVertices, c.degenerateFaces, c.components, c.selfIntersections})
    p.put(std::uint64_t(n));
  p.put(std::int64_t(c.genus));
  p.put(c.volume);
}

SurfaceCheck getSurfaceCheck(SectionUnpacker& u) {
  SurfaceCheck c;
  for (std::size_t* n : {&c.vertices, &c.edges, &c.faces, &c.boundaryEdges, &c.nonManifoldEdges, &c.nonManifoldVertices, &c.misorientedEdges,
                         &c.isolatedVertices, &c.degenerateFaces, &c.components, &c.selfIntersections})
    *n = std::size_t(u.get<std::uint64_t>());
  c.genus = int(u.get<std::int64_t>());
  c.volume = u.get<double>();
  return c;
}

void putLabelGrid(SectionPacker& p, const LabelGrid& g) {
  putGeometry(p, g.geometry());
  p.putVector(g.labels());
}

LabelGrid getLabelGrid(SectionUnpacker& u, const std::string& source) {
  const GridGeometry g = getGeometry(u, source);
  std::vector<Label> labels = u.getVector<Label>();
  if (std::int64_t(labels.size()) != g.voxelCount())
    u.invalid(std::to_string(labels.size()) + " labels for a grid of " + std::to_string(g.voxelCount()) + " voxels");
  LabelGrid grid;
  grid.geometry() = g;
  grid.labels() = std::move(labels);
  return grid;
}

void putSkeleton(SectionPacker& p, const skeleton::Skeleton& s) {
  const skeleton::BodyParts& b = s.parts;
  putLabelGrid(p, b.parts);
  putVector3(p, b.frame.right);
  putVector3(p, b.frame.anterior);
  putVector3(p, b.frame.superior);
  putVector3(p, b.frame.midpoint);
  p.put(std::uint8_t(b.frame.fromBones));
  p.put(std::uint64_t(b.bones.size()));
  for (const skeleton::BoneVoxels& v : b.bones) {
    p.put(std::uint8_t(v.bone));
    p.put(std::uint8_t(v.side));
    p.putVector(v.voxels);
  }
  for (const std::int64_t n : b.voxels) p.put(n);
  for (const std::vector<skeleton::Bone>& seeds : b.seedBones) {
    std::vector<std::uint8_t> bytes;
    for (const skeleton::Bone bone : seeds) bytes.push_back(std::uint8_t(bone));
    p.putVector(bytes);
  }
  p.put(b.reachedThroughSkin);
  p.put(b.reachedThroughBackground);
  p.put(std::uint64_t(s.joints.size()));
  for (const skeleton::Joint& j : s.joints) {
    p.put(std::uint8_t(j.id));
    for (const Eigen::Vector3d* v : {&j.centre, &j.longAxis, &j.leftRight, &j.anterior, &j.superior}) putVector3(p, *v);
    p.put(j.radius);
    p.putString(j.method);
    p.putString(j.axisMethod);
  }
  p.put(s.seconds);
}

skeleton::Skeleton getSkeleton(SectionUnpacker& u, const std::string& source) {
  skeleton::Skeleton s;
  skeleton::BodyParts& b = s.parts;
  b.parts = getLabelGrid(u, source);
  for (const Label l : b.parts.labels())
    if (l > skeleton::kPartCount) u.invalid("body part " + std::to_string(l) + " (at most " + std::to_string(skeleton::kPartCount) + ")");
  b.frame.right = getVector3(u);
  b.frame.anterior = getVector3(u);
  b.frame.superior = getVector3(u);
  b.frame.midpoint = getVector3(u);
  b.frame.fromBones = u.get<std::uint8_t>() != 0;
  const std::size_t bones = u.getCount(2 + 8);
  for (std::size_t i = 0; i < bones; ++i) {
    skeleton::BoneVoxels v;
    const auto bone = u.get<std::uint8_t>(), side = u.get<std::uint8_t>();
    if (bone > skeleton::kBoneCount || side > 2) u.invalid("bone " + std::to_string(bone) + " side " + std::to_string(side));
    v.bone = skeleton::Bone(bone);
    v.side = skeleton::Side(side);
    v.voxels = u.getVector<std::int64_t>();
    for (const std::int64_t x : v.voxels)
      if (x < 0 || x >= b.parts.voxelCount()) u.invalid("bone voxel " + std::to_string(x) + " outside the grid");
    b.bones.push_back(std::move(v));
  }
  for (std::int64_t& n : b.voxels) n = u.get<std::int64_t>();
  for (std::vector<skeleton::Bone>& seeds : b.seedBones)
    for (const std::uint8_t bone : u.getVector<std::uint8_t>()) {
      if (bone > skeleton::kBoneCount) u.invalid("seed bone " + std::to_string(bone));
      seeds.push_back(skeleton::Bone(bone));
    }
  b.reachedThroughSkin = u.get<std::int64_t>();
  b.reachedThroughBackground = u.get<std::int64_t>();
  const std::size_t joints = u.getCount(1 + 15 * 8 + 8 + 16);
  for (std::size_t i = 0; i < joints; ++i) {
    skeleton::Joint j;
    const auto id = u.get<std::uint8_t>();
    if (id >= skeleton::kJointCount) u.invalid("joint " + std::to_string(id));
    j.id = skeleton::JointId(id);
    for (Eigen::Vector3d* v : {&j.centre, &j.longAxis, &j.leftRight, &j.anterior, &j.superior}) *v = getVector3(u);
    j.radius = u.get<double>();
    j.method = u.getString();
    j.axisMethod = u.getString();
    s.joints.push_back(std::move(j));
  }
  s.seconds = u.get<double>();
  return s;
}

void putInputs(SectionPacker& p, const PreparedInputs& in) {
  p.put(std::uint64_t(in.files.size()));
  for (const InputDigest& d : in.files) {
    p.putString(d.role);
    p.putString(d.path);
    p.putString(d.sha256);
    p.put(d.bytes);
  }
  p.put(std::int64_t(in.workingFactor));
  for (const std::int64_t d : in.workingDims) p.put(d);
  p.putString(in.build);
}

PreparedInputs getInputs(SectionUnpacker& u) {
  PreparedInputs in;
  const std::size_t n = u.getCount(3 * 8 + 8);
  for (std::size_t i = 0; i < n; ++i) {
    InputDigest d;
    d.role = u.getString();
    d.path = u.getString();
    d.sha256 = u.getString();
    d.bytes = u.get<std::uint64_t>();
    in.files.push_back(std::move(d));
  }
  const auto factor = u.get<std::int64_t>();
  if (factor < 1 || factor > 1024) u.invalid("working factor " + std::to_string(factor));
  in.workingFactor = int(factor);
  for (std::int64_t& d : in.workingDims) d = u.get<std::int64_t>();
  in.build = u.getString();
  return in;
}

const InputDigest* findRole(const std::vector<InputDigest>& files, const std::string& role) {
  for (const InputDigest& d : files)
    if (d.role == role) return &d;
  return nullptr;
}

std::string roleWords(const std::string& role) {
  if (role == "grid") return "grid";
  if (role == "grid data") return "grid data file";
  if (role == "organs") return "organ table";
  if (role == "parts") return "parts grid (--parts)";
  return role;
}

std::string shortSha(const std::string& sha) { return sha.substr(0, 12); }

}  // namespace

// ---- keys -------------------------------------------------------------

std::string gridDigest(const LabelGrid& grid) {
  FastHash h;
  hashGeometry(h, grid.geometry());
  h.update(grid.data(), grid.labels().size() * sizeof(Label));
  return h.hex();
}

std::string gridDigest(const ScalarGrid& grid) {
  FastHash h;
  hashGeometry(h, grid.geometry);
  h.update(grid.values.data(), grid.values.size() * sizeof(float));
  return h.hex();
}

std::string separationsKey(const std::vector<LimbSeparation>& separations) {
  std::string s;
  for (const LimbSeparation& l : separations) {
    s += std::to_string(l.groupA) + ":" + std::to_string(l.groupB);
    if (l.region)
      for (int a = 0; a < 3; ++a) s += "," + exact(l.region->min()[a]) + "," + exact(l.region->max()[a]);
    s += ";";
  }
  return s;
}

std::string cageOptionsKey(const CageOptions& o) {
  return "dilation " + exact(o.dilationMm) + " vertices " + std::to_string(o.targetVertices) + " facet " + exact(o.facetSizeMm) + " " +
         exact(o.facetDistanceMm) + " erosion " + exact(o.erosionMm) + " slope " + exact(o.separationSlope) + " separations " +
         separationsKey(o.separations);
}

std::string envelopeOptionsKey(const EnvelopeOptions& o) {
  return "smoothing " + exact(o.smoothingMm) + " facet " + exact(o.facetSizeMm) + " " + exact(o.facetDistanceMm) + " " + exact(o.facetAngleDeg);
}

std::string transferMeshOptionsKey(const TransferMeshOptions& o) {
  return "offset " + exact(o.boundaryOffsetVoxels) + " facet " + exact(o.facetDistanceVoxels) + " " + exact(o.facetAngleDeg) + " ratio " +
         exact(o.radiusEdgeRatio) + (o.coverageCaps ? " caps" : "");
}

std::string articulatedMeshOptionsKey(const ArticulatedMeshOptions& o) {
  std::string k = "articulated";
  for (const double v : {o.fineSizeVoxels, o.coarseSizeMm, o.gradingMm, o.trunkBoneReachMm, o.pelvisBoneReachMm, o.jointClearanceMm,
                         o.wholePartBoneClearanceMm, o.wholePartOwnBoneClearanceMm, o.bodyMarginVoxels, o.minBodyRadiusVoxels,
                         o.attachmentHalfAngleDeg, o.elbowAttachmentHalfAngleDeg, o.ownerShellVoxels, o.hingeOwnerReachMm,
                         o.yieldingShellVoxels, o.limbCutMarginRadii, o.legTrunkCutBehindMm, o.boneGapMm, o.boneGapReachMm})
    k += " " + exact(v);
  k += " whole";
  for (const skeleton::Part p : o.rigidWholeParts) k += " " + std::to_string(int(p));
  k += " yielding";
  for (const skeleton::JointId j : o.yieldingShellJoints) k += " " + std::to_string(int(j));
  k += " gaps";
  for (const skeleton::JointId j : o.boneGapJoints) k += " " + std::to_string(int(j));
  for (const bool b : {o.wristBodies, o.movingScapulae, o.movingPatellae, o.boneGapKeepsSkin}) k += b ? " 1" : " 0";
  if (o.boneGapBesideCuts) k += " beside-cuts";
  if (o.cutOffTissueRigid) k += " cut-off-rigid";
  k += " legs " + std::to_string(int(o.legTrunkCut));
  return k + " mesh " + transferMeshOptionsKey(o.transferMesh);
}

std::string separationsText(const std::vector<LimbSeparation>& separations, const GridGeometry& grid) {
  if (separations.empty()) return "none";
  std::string s;
  for (const LimbSeparation& l : separations) {
    if (!s.empty()) s += ", ";
    s += groupName(l.groupA) + ":" + groupName(l.groupB);
    if (l.region) {
      Eigen::AlignedBox3d world;
      for (int c = 0; c < 8; ++c) world.extend(gridToWorld(grid, l.region->corner(Eigen::AlignedBox3d::CornerType(c))));
      s += "@" + formatNumber("%g", world.min().x()) + "," + formatNumber("%g", world.min().y()) + "," + formatNumber("%g", world.min().z()) +
           "," + formatNumber("%g", world.max().x()) + "," + formatNumber("%g", world.max().y()) + "," + formatNumber("%g", world.max().z());
    }
  }
  return s;
}

std::string cageOptionsText(const CageOptions& o) {
  return "--dilation " + formatNumber("%g", o.dilationMm) + " mm, --vertices " + std::to_string(o.targetVertices);
}

PreparedInputs preparedInputs(const std::string& grid, const std::optional<OrganTable>& organs, const std::string& organsSource,
                              const std::string& parts, int workingFactor, const Index3& workingDims) {
  PreparedInputs in;
  in.files = makeProvenance("", {{"grid", grid}, {"parts", parts}}).inputs;
  if (organs) {
    std::string text;
    for (const auto& [id, organ] : organs->organs())
      text += std::to_string(id) + "\t" + organ.name + "\t" + std::to_string(organ.tissue) + "\t" + exact(organ.density) + "\n";
    in.files.push_back({"organs", organsSource, sha256Hex(text), text.size()});
  }
  in.workingFactor = workingFactor;
  in.workingDims = workingDims;
  in.build = voxmorphVersionLine();
  return in;
}

// ---- lookups and refusals ---------------------------------------------

namespace {

// The stored piece whose key is `key`, or nullptr.
template <class Piece>
const Piece* findByKey(const std::vector<Piece>& pieces, const std::string& key) {
  for (const Piece& p : pieces)
    if (p.key == key) return &p;
  return nullptr;
}

}  // namespace

const PreparedCage* PreparedState::findCage(const std::string& key) const { return findByKey(cages, key); }
const PreparedEnvelope* PreparedState::findEnvelope(const std::string& key) const { return findByKey(envelopes, key); }
const PreparedTransferMesh* PreparedState::findMesh(const std::string& key) const { return findByKey(meshes, key); }
const PreparedArticulatedMesh* PreparedState::findArticulatedMesh(const std::string& key) const {
  return findByKey(articulatedMeshes, key);
}

void PreparedState::refuseCage(const PreparedCageQuery& q) const {
  const std::string hint = "; voxmorph prepare --pose POSE (with the same --separate, --dilation, --vertices) adds it";
  if (cages.empty()) throw InputError(source, "holds no cage (prepared with --cage?)" + hint);
  // The stored cage nearest the query: most of separations, options, groups equal.
  const PreparedCage* best = &cages.front();
  int bestScore = -1;
  for (const PreparedCage& c : cages) {
    const int score = 4 * (c.separations == q.separations) + 2 * (c.options == q.options) + (c.groups == q.groups);
    if (score > bestScore) {
      bestScore = score;
      best = &c;
    }
  }
  std::string held;
  for (const PreparedCage& c : cages) held += std::string(held.empty() ? "" : "; ") + c.separations;
  if (best->separations != q.separations)
    throw InputError(source, "prepared for other separations (" + held + "), not this run's (" + q.separations + ")" + hint);
  if (best->options != q.options)
    throw InputError(source, "prepared with other cage options (" + best->options + "), not this run's (" + q.options + ")" + hint);
  throw InputError(source, "prepared with other label groups (" + best->groups + "), not this run's (" + q.groups + ")" + hint);
}

namespace {

// A transfer mesh's key (PreparedMeshQuery::key): three digests (group
// grid, label groups, sizing field), the mesh options' text, " cuts ", the
// cuts. Its digests and its options.
std::pair<std::string, std::string> meshKeyParts(const std::string& key) {
  std::size_t at = 0;
  for (int digest = 0; digest < 3 && at != std::string::npos; ++digest) at = key.find(' ', at == 0 ? 0 : at + 1);
  const std::size_t cuts = key.rfind(" cuts ");
  if (at == std::string::npos || cuts == std::string::npos || cuts < at) return {key, ""};
  return {key.substr(0, at), key.substr(at + 1, cuts - at - 1)};
}

}  // namespace

void PreparedState::refuseMesh(const PreparedMeshQuery& q) const {
  const std::string hint = "; voxmorph prepare --pose POSE adds it";
  std::string held;
  for (const PreparedTransferMesh& m : meshes) held += std::string(held.empty() ? "" : "; ") + m.cuts;
  // A mesh of this run's cuts that differs in its options or inputs.
  const auto [digests, options] = meshKeyParts(q.key);
  for (const PreparedTransferMesh& m : meshes) {
    if (m.cuts != q.cuts) continue;
    const auto [heldDigests, heldOptions] = meshKeyParts(m.key);
    if (heldOptions != options)
      throw InputError(source, "holds this run's transfer mesh built with other options (" + heldOptions + "), not this run's (" + options +
                                   "); voxmorph prepare makes it again");
    if (heldDigests != digests)
      throw InputError(source, "holds this run's transfer mesh of other label groups or another sizing field" + hint);
  }
  throw InputError(source, "holds no transfer mesh cut as this run cuts it (" + q.cuts + "; it holds: " + (held.empty() ? "none" : held) + ")" +
                               hint);
}

void PreparedState::refuseEnvelope() const {
  throw InputError(source, "holds no envelope of this run's label groups; voxmorph prepare --pose POSE adds it");
}

std::string PreparedState::check(const PreparedInputs& run) const {
  for (const char* role : {"grid", "grid data", "organs", "parts"}) {
    const InputDigest* had = findRole(inputs.files, role);
    const InputDigest* has = findRole(run.files, role);
    if (!had && !has) continue;
    if (had && !has)
      throw InputError(source, "prepared with " + std::string(std::string(role) == "organs" ? "an " : "a ") + roleWords(role) + " (" +
                                   had->path + "), this run has none");
    if (!had && has)
      throw InputError(source, "prepared without a " + roleWords(role) + ", this run has one (" + has->path + ")");
    if (had->sha256 != has->sha256)
      throw InputError(source, "prepared from another " + roleWords(role) + " (" + had->path + ", SHA-256 " + shortSha(had->sha256) +
                                   "...), not " + has->path + " (SHA-256 " + shortSha(has->sha256) + "...): voxmorph prepare makes it again");
  }
  if (inputs.workingFactor != run.workingFactor || inputs.workingDims != run.workingDims)
    throw InputError(source, "prepared on a working grid downsampled by " + std::to_string(inputs.workingFactor) + ", this run's is by " +
                                 std::to_string(run.workingFactor));
  if (inputs.build != run.build)
    return source + ": prepared by " + inputs.build + ", this is " + run.build +
           "; if the pre-processing changed in between, results differ from a run without --prepared (voxmorph prepare makes it again)";
  return "";
}

std::string PreparedState::summary() const {
  std::string s;
  if (skeleton) {
    s += "skeleton: " + std::to_string(skeleton->joints.size()) + " joints, " + std::to_string(skeleton->parts.bones.size()) + " bone sets\n";
  } else {
    s += "skeleton: none (the organ table names no bones)\n";
  }
  for (const PreparedCage& c : cages)
    s += "cage: " + std::to_string(c.cage.vertexCount()) + " vertices, " + std::to_string(c.cage.faceCount()) + " faces; separations " +
         c.separations + "; " + c.options + "; " + c.groups + "\n";
  for (const PreparedEnvelope& e : envelopes)
    s += "envelope: " + std::to_string(e.envelope.vertexCount()) + " vertices, " + std::to_string(e.envelope.faceCount()) + " faces\n";
  for (const PreparedTransferMesh& m : meshes)
    s += "transfer mesh: " + std::to_string(m.mesh.vertexCount()) + " vertices, " + std::to_string(m.mesh.tetCount()) + " tets; cuts " +
         m.cuts + "\n";
  for (const PreparedArticulatedMesh& m : articulatedMeshes)
    s += "articulated transfer mesh: " + std::to_string(m.mesh.mesh.vertexCount()) + " vertices, " + std::to_string(m.mesh.mesh.tetCount()) +
         " tets, " + std::to_string(m.mesh.bodies.size()) + " articular bodies\n";
  return s;
}

// ---- file -------------------------------------------------------------

std::string PreparedState::bytes() const {
  SectionFileWriter w(kKind);
  {
    SectionPacker p;
    putInputs(p, inputs);
    w.add("inputs", p.bytes());
  }
  if (skeleton) {
    SectionPacker p;
    putSkeleton(p, *skeleton);
    w.add("skeleton", p.bytes());
  }
  for (std::size_t i = 0; i < cages.size(); ++i) {
    const PreparedCage& c = cages[i];
    SectionPacker p;
    for (const std::string* s : {&c.key, &c.groups, &c.separations, &c.options}) p.putString(*s);
    putTriMesh(p, c.cage);
    p.put(std::uint64_t(c.report.meshedVertices));
    p.put(c.report.erodedVoxels);
    p.put(c.report.foregroundOutside);
    putSurfaceCheck(p, c.report.check);
    w.add("cage " + std::to_string(i), p.bytes());
  }
  for (std::size_t i = 0; i < envelopes.size(); ++i) {
    SectionPacker p;
    p.putString(envelopes[i].key);
    putTriMesh(p, envelopes[i].envelope);
    w.add("envelope " + std::to_string(i), p.bytes());
  }
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    const PreparedTransferMesh& m = meshes[i];
    SectionPacker p;
    p.putString(m.key);
    p.putString(m.cuts);
    putTetMesh(p, m.mesh);
    p.put(std::uint64_t(m.cutReports.size()));
    for (const CutReport& c : m.cutReports) putCutReport(p, c);
    p.put(m.uncoveredVoxels);
    w.add("transfer mesh " + std::to_string(i), p.bytes());
  }
  for (std::size_t i = 0; i < articulatedMeshes.size(); ++i) {
    SectionPacker p;
    p.putString(articulatedMeshes[i].key);
    putArticulatedMesh(p, articulatedMeshes[i].mesh);
    w.add("articulated mesh " + std::to_string(i), p.bytes());
  }
  return w.bytes();
}

void PreparedState::write(const std::string& path) const { writeFileAtomic(path, bytes()); }

PreparedState PreparedState::read(const std::string& path) { return unpackState(SectionFile::read(path, kKind)); }

PreparedState PreparedState::fromBytes(std::string bytes, const std::string& source) {
  return unpackState(SectionFile::parse(std::move(bytes), source, kKind));
}

PreparedState PreparedState::unpackState(const SectionFile& file) {
  const std::string& path = file.source();
  std::string bytes;
  PreparedState s;
  s.source = path;
  {
    SectionUnpacker u = file.unpacker("inputs", bytes);
    s.inputs = getInputs(u);
    u.finish();
  }
  if (file.has("skeleton")) {
    SectionUnpacker u = file.unpacker("skeleton", bytes);
    s.skeleton = getSkeleton(u, path);
    u.finish();
  }
  for (const std::string& name : file.names()) {
    if (name.rfind("cage ", 0) == 0) {
      SectionUnpacker u = file.unpacker(name, bytes);
      PreparedCage c;
      for (std::string* t : {&c.key, &c.groups, &c.separations, &c.options}) *t = u.getString();
      c.cage = getTriMesh(u, path + " (" + name + ")");
      c.report.meshedVertices = std::size_t(u.get<std::uint64_t>());
      c.report.erodedVoxels = u.get<std::int64_t>();
      c.report.foregroundOutside = u.get<std::int64_t>();
      c.report.check = getSurfaceCheck(u);
      u.finish();
      s.cages.push_back(std::move(c));
    } else if (name.rfind("envelope ", 0) == 0) {
      SectionUnpacker u = file.unpacker(name, bytes);
      PreparedEnvelope e;
      e.key = u.getString();
      e.envelope = getTriMesh(u, path + " (" + name + ")");
      u.finish();
      s.envelopes.push_back(std::move(e));
    } else if (name.rfind("transfer mesh ", 0) == 0) {
      SectionUnpacker u = file.unpacker(name, bytes);
      PreparedTransferMesh m;
      m.key = u.getString();
      m.cuts = u.getString();
      m.mesh = getTetMesh(u, path + " (" + name + ")");
      const std::size_t cuts = u.getCount(4 * 8 + 8);
      for (std::size_t i = 0; i < cuts; ++i) m.cutReports.push_back(getCutReport(u, m.mesh.vertexCount()));
      m.uncoveredVoxels = u.get<std::int64_t>();
      u.finish();
      s.meshes.push_back(std::move(m));
    } else if (name.rfind("articulated mesh ", 0) == 0) {
      SectionUnpacker u = file.unpacker(name, bytes);
      PreparedArticulatedMesh m;
      m.key = u.getString();
      m.mesh = getArticulatedMesh(u, path + " (" + name + ")");
      u.finish();
      s.articulatedMeshes.push_back(std::move(m));
    } else if (name != "inputs" && name != "skeleton") {
      throw InputError(path, "unknown section '" + name + "'");
    }
  }
  return s;
}


}  // namespace vox
