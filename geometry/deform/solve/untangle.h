#pragma once
// Untangling a tet mesh whose fixed vertices are where they must be and
// whose free vertices leave some tets inverted: the free vertices minimise
// an energy that stays finite on inverted tets, with a regularisation that
// shrinks round by round until every tet is positive (Garanzha, Kaporin,
// Kudryavtseva, Protais, Ray, Sokolov 2021, "Foldover-free maps in 50 lines
// of code"). Per tet t, with J its deformation gradient (rest to now) and
// D = det J:
//
//   f_eps(J) = ||J||_F^2 / chi(D)^(2/3) + lambda (D^2 + 1) / chi(D),
//   chi(D) = (D + sqrt(eps^2 + D^2)) / 2,
//
// weighted by the tet's rest volume. chi is positive for every D, so an
// inverted tet has a finite energy that falls as it unfolds; as eps goes to
// zero, f_eps goes to infinity on flat and inverted tets (a barrier), and
// at a rotation it is 3 + 2 lambda (the first term measures shape, the
// second volume). Soft anchors hold chosen vertices near given places
// (w_k (m_k / |Omega|) ||x_k - a_k||^2 / h^2, as the injective solve's soft
// targets). Each round minimises E_eps by L-BFGS (LBFGS++), then sets eps
// from the smallest D and the round's decrease of E; the round with the
// fewest inverted tets is kept, so a tangle that cannot be undone (two
// fixed bones too close for the tissue between) is left no worse. The solve of the
// posing (injective_solve.h) keeps a mesh injective from an injective start;
// this takes one that is not there.

#include "geometry/tet_mesh.h"

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

namespace vox {

struct UntangleOptions {
  // lambda. At 1 the tissue about a tangle that cannot be undone swells
  // (the phone call's and seated region by 4.5 to 4.7 %) to make room; at 10 it
  // keeps its volume within a percent for a quarter more tets left folded.
  double volumeWeight = 10.0;
  int rounds = 150;           // eps rounds at most
  int iterationsPerRound = 200;  // L-BFGS iterations per round at most
  // The first round's eps at most (it is taken from the smallest det J).
  double initialEpsilon = 1.0;
  // While tets are still inverted, the rounds stop after this many without
  // fewer of them (the best round's positions are kept).
  int patience = 40;
  // After every tet is positive, rounds go on while E falls by more than
  // this fraction a round (the tets move away from the barrier).
  double tolerance = 1e-3;
  // Every tet must end at least this relative volume (det J) to count as
  // untangled.
  double minRelativeVolume = 1e-3;
  // Among the rounds with the fewest inverted tets, keep the one of the
  // lowest energy (not the largest smallest det J), and take the result
  // whenever it has no more inverted tets than the input: the anchors are
  // then what the solve is for (contact targets), not only the unfolding.
  bool lowestEnergy = false;
  int threads = 0;  // workerThreads
};

struct UntangleReport {
  std::size_t freeVertices = 0, tets = 0;  // the tets with a free vertex
  std::size_t invertedBefore = 0, invertedAfter = 0;  // of those tets, det J <= minRelativeVolume
  double minRelativeVolumeBefore = 0.0, minRelativeVolumeAfter = 0.0;
  int rounds = 0, iterations = 0;
  bool untangled = false;  // every tet at least minRelativeVolume
  double seconds = 0.0;
};

struct UntangleAnchor {
  std::int32_t vertex;
  Eigen::Vector3d target;
  double weight;
};

// Moves the vertices with free[v] != 0 in `positions`; the others stay.
// Only tets with a free vertex are considered (the others cannot change).
// Throws InputError on a rest tet that is flat or inverted, or an index out
// of range. The positions are changed only where the result has fewer
// inverted tets than the input had, or as many with a larger smallest
// det J (with options.lowestEnergy: no more inverted tets); otherwise they
// are left as given (report.untangled false).
UntangleReport untangleTets(std::span<const Eigen::Vector3d> rest, std::span<const Tet> tets,
                            std::span<const std::uint8_t> free, std::span<const UntangleAnchor> anchors,
                            std::vector<Eigen::Vector3d>& positions, const UntangleOptions& options = {});

}  // namespace vox
