#include "geometry/deform/solve/frame_deformer.h"

#include "geometry/error.h"
#include "geometry/nearest_vertex.h"
#include "geometry/parallel.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <limits>
#include <numeric>
#include <string>

namespace vox {

namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

Eigen::Vector4d barycentric(const std::vector<Eigen::Vector3d>& p, const Tet& t, const Eigen::Vector3d& q) {
  Eigen::Matrix3d e;
  const Eigen::Vector3d& a = p[std::size_t(t[0])];
  e.col(0) = p[std::size_t(t[1])] - a;
  e.col(1) = p[std::size_t(t[2])] - a;
  e.col(2) = p[std::size_t(t[3])] - a;
  const Eigen::Vector3d l = e.partialPivLu().solve(q - a);
  return {1.0 - l.sum(), l[0], l[1], l[2]};
}

}  // namespace

void FrameDeformer::precompute(const TriMesh& cage, std::span<const Eigen::Vector3d> envelope, const TetMesh& transferMesh,
                               std::span<const std::int32_t> handles, const FrameDeformerOptions& options) {
  restCage_ = cage;
  stats_ = {};
  transferMesh.validate("transfer mesh");

  auto start = Clock::now();
  envelopeInside_ = insideCage(cage, envelope);
  tmInside_ = insideCage(cage, transferMesh.positions);
  if (options.propagateAnyway.size() == tmInside_.size())
    for (std::size_t v = 0; v < tmInside_.size(); ++v) tmInside_[v] = tmInside_[v] && !options.propagateAnyway[v];
  stats_.classifyMs = millisecondsSince(start);

  envelopeInsideIds_.clear();
  tmInsideIds_.clear();
  std::vector<Eigen::Vector3d> points;
  for (std::size_t v = 0; v < envelope.size(); ++v)
    if (envelopeInside_[v]) {
      envelopeInsideIds_.push_back(std::int32_t(v));
      points.push_back(envelope[v]);
    }
  stats_.envelopeInside = envelopeInsideIds_.size();
  stats_.envelopeOutside = envelope.size() - envelopeInsideIds_.size();
  envelopeInsideRest_ = points;
  start = Clock::now();
  envelopeGreen_ = greenCoordinates(cage, points, options.precision);
  stats_.greenEnvelopeMs = millisecondsSince(start);

  points.clear();
  for (std::size_t v = 0; v < transferMesh.vertexCount(); ++v)
    if (tmInside_[v]) {
      tmInsideIds_.push_back(std::int32_t(v));
      points.push_back(transferMesh.positions[v]);
    }
  stats_.transferMeshInside = tmInsideIds_.size();
  stats_.transferMeshOutside = transferMesh.vertexCount() - tmInsideIds_.size();
  tmInsideRest_ = points;
  start = Clock::now();
  tmGreen_ = greenCoordinates(cage, points, options.precision);
  stats_.greenTransferMeshMs = millisecondsSince(start);

  start = Clock::now();
  arap_.precompute(cage, handles);
  stats_.arapFactorMs = millisecondsSince(start);

  // Rigid bone groups, fitted to their Green-coordinate vertices; every
  // placed vertex is known to the propagation.
  rigidBones_.precompute(options.rigidGroups, tmInside_, transferMesh.positions);
  std::vector<std::uint8_t> known = tmInside_;
  for (std::size_t v = 0; v < known.size(); ++v)
    if (!rigidBones_.placed().empty() && rigidBones_.placed()[v]) {
      known[v] = 1;
      ++stats_.rigidVertices;
    }
  const int bandRings = options.rigidBandRings;
  if (bandRings > 0 && stats_.rigidVertices > 0) {
    std::vector<std::vector<std::int32_t>> neighbours(transferMesh.vertexCount());
    for (const Tet& t : transferMesh.tets)
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
          if (a != b) neighbours[std::size_t(t[std::size_t(a)])].push_back(t[std::size_t(b)]);
    std::vector<std::uint8_t> band(known.size(), 0);
    std::vector<std::int32_t> front;
    for (std::size_t v = 0; v < known.size(); ++v)
      if (rigidBones_.placed()[v]) front.push_back(std::int32_t(v));
    for (int ring = 0; ring < bandRings; ++ring) {
      std::vector<std::int32_t> next;
      for (const std::int32_t v : front)
        for (const std::int32_t n : neighbours[std::size_t(v)])
          if (!rigidBones_.placed()[std::size_t(n)] && !band[std::size_t(n)]) {
            band[std::size_t(n)] = 1;
            next.push_back(n);
          }
      front = std::move(next);
    }
    for (std::size_t v = 0; v < known.size(); ++v)
      if (band[v]) known[v] = 0;
  }
  stats_.rigidGroups = rigidBones_.groups();
  stats_.rigidGroupsDropped = rigidBones_.droppedGroups();

  start = Clock::now();
  propagation_.precompute(transferMesh, known);
  stats_.propagation = propagation_.diagnostics();
  stats_.propagationFactorMs = millisecondsSince(start);

  // Envelope vertices outside the cage ride on the TM tet around them: the
  // tet incident to the nearest TM vertex that contains the point best
  // (largest smallest barycentric weight; slightly negative weights
  // extrapolate the tet's affine map to points just off the TM).
  start = Clock::now();
  attachments_.clear();
  if (stats_.envelopeOutside > 0) {
    if (transferMesh.tetCount() == 0)
      throw InputError("envelope", std::to_string(stats_.envelopeOutside) +
                                       " vertices lie outside the cage and there is no transfer mesh to carry them");
    std::vector<std::vector<std::int32_t>> incident(transferMesh.vertexCount());
    for (std::size_t t = 0; t < transferMesh.tetCount(); ++t)
      for (std::int32_t v : transferMesh.tets[t]) incident[std::size_t(v)].push_back(std::int32_t(t));
    std::vector<std::int32_t> used;
    for (std::size_t v = 0; v < incident.size(); ++v)
      if (!incident[v].empty()) used.push_back(std::int32_t(v));
    const NearestVertex nearest(transferMesh.positions, used);
    for (std::size_t v = 0; v < envelope.size(); ++v) {
      if (envelopeInside_[v]) continue;
      const std::int32_t near = nearest.query(envelope[v]);
      Attachment best{std::int32_t(v), {}, Eigen::Vector4d::Zero()};
      double bestScore = -std::numeric_limits<double>::infinity();
      for (std::int32_t t : incident[std::size_t(near)]) {
        const Eigen::Vector4d w = barycentric(transferMesh.positions, transferMesh.tets[std::size_t(t)], envelope[v]);
        if (w.minCoeff() > bestScore) {
          bestScore = w.minCoeff();
          best.tet = transferMesh.tets[std::size_t(t)];
          best.weights = w;
        }
      }
      attachments_.push_back(best);
    }
  }
  stats_.attachMs = millisecondsSince(start);

  envelope_.assign(envelope.begin(), envelope.end());
  transferMesh_ = transferMesh.positions;
  restEnvelope_ = envelope_;
  restTransferMesh_ = transferMesh_;
  timings_ = {};
}

void FrameDeformer::setHandles(std::span<const std::int32_t> handles) {
  const auto start = Clock::now();
  arap_.precompute(restCage_, handles);
  stats_.arapFactorMs = millisecondsSince(start);
}

void FrameDeformer::update(const Eigen::MatrixX3d& handleTargets, int arapIterations, std::span<const Eigen::Isometry3d> rigidMotions) {
  const auto frameStart = Clock::now();
  auto start = frameStart;
  const std::vector<Eigen::Vector3d>& cage = arap_.solve(handleTargets, arapIterations);
  timings_.arap = millisecondsSince(start);
  // The rest cage gives the rest pose, bit for bit (the propagation solve
  // would reproduce it only up to rounding), so an identity pose rasterizes
  // to the input grid exactly.
  if (cage == restCage_.positions) {
    start = Clock::now();
    transferMesh_ = restTransferMesh_;
    envelope_ = restEnvelope_;
    timings_ = {.arap = timings_.arap, .envelopeOutside = millisecondsSince(start), .total = millisecondsSince(frameStart)};
    return;
  }

  // Displacement form: the rest pose comes out exactly, and float or half
  // coordinates err in proportion to how far the cage moved.
  start = Clock::now();
  const GreenCageFrame frame = greenCageDisplacement(restCage_, cage, tmGreen_.stride());
  tmScratch_.resize(tmInsideIds_.size());
  applyGreenCoordinates(tmGreen_, frame, tmScratch_, tmInsideRest_);
  for (std::size_t k = 0; k < tmInsideIds_.size(); ++k) transferMesh_[std::size_t(tmInsideIds_[k])] = tmScratch_[k];
  timings_.greenTransferMesh = millisecondsSince(start);
  start = Clock::now();
  rigidBones_.apply(transferMesh_, rigidMotions);
  timings_.rigidBones = millisecondsSince(start);

  // The envelope product (memory bound) and the propagation solves (compute
  // bound, they need only the TM) share the cores: one task for the solves,
  // the envelope rows cut into blocks, all handed out dynamically.
  start = Clock::now();
  envelopeScratch_.resize(envelopeInsideIds_.size());
  const std::size_t rows = envelopeScratch_.size();
  const std::size_t blocks = std::min<std::size_t>(32, (rows + 1023) / 1024);
  parallelFor(std::int64_t(blocks) + 1, 0, [&](std::int64_t task) {
    if (task == 0) {
      const auto solveStart = Clock::now();
      propagation_.propagate(transferMesh_);
      timings_.propagation = millisecondsSince(solveStart);
      return;
    }
    const std::size_t block = std::size_t(task - 1);
    applyGreenCoordinateRows(envelopeGreen_, frame, rows * block / blocks, rows * (block + 1) / blocks, envelopeScratch_,
                             envelopeInsideRest_);
  });
  for (std::size_t k = 0; k < envelopeInsideIds_.size(); ++k) envelope_[std::size_t(envelopeInsideIds_[k])] = envelopeScratch_[k];
  timings_.greenEnvelope = millisecondsSince(start);

  start = Clock::now();
  for (const Attachment& a : attachments_) {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) p += a.weights[k] * transferMesh_[std::size_t(a.tet[std::size_t(k)])];
    envelope_[std::size_t(a.vertex)] = p;
  }
  timings_.envelopeOutside = millisecondsSince(start);
  timings_.total = millisecondsSince(frameStart);
}

}  // namespace vox
