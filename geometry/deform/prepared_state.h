#pragma once
// The rest state of a grid, saved once by `voxmorph prepare` and taken by
// `deform`, `render --pose` and `view` (--prepared) instead of rebuilding it
// for every pose: what DeformationPipeline and deformGrid compute from the
// rest grid before the pose.
//
//  - inputs: the SHA-256 of the grid file (and of its data file), of the
//    organ table and of the parts grid it was made from, the working grid
//    (downsampling factor and geometry) and the voxmorph build that made it;
//  - the skeleton (body parts, bones, anatomical frame, joints), when the
//    organ table names bones;
//  - per label-group grid and cage options: the automatic cage and its
//    report; per label-group grid: the envelope; per (transfer-mesh group
//    grid, sizing field, cuts): the cut transfer mesh, its cut reports and
//    its uncovered voxels; with `prepare --articulated`, the articulated
//    transfer mesh (articulated_mesh.h) per set of its options. Each is
//    found by a key: a digest of the grid it
//    was built from and the canonical text of the options that shape it, so
//    a pipeline takes a stored piece only where it would have built the same
//    one (byte-identical results), and a prepared state holds one cage and
//    transfer mesh per set of separations it was prepared for (the poses
//    `prepare --pose` names).
//
// Recomputed on load (cheap against their storage): the label groups, the
// nearest groups of the cage vertices, the bone keys and rigid bone groups,
// the sizing field, and the embedding (Green coordinates, ARAP and
// propagation factorizations: they depend on the pose's handles, and the
// coordinates alone would take about 200 MB on the AM).
//
// The file (extension .vxprep) is a SectionFile (io/section_file.h): magic
// "VXPREP\r\n", format version kPreparedStateVersion, zlib-compressed
// sections, a CRC-32; the reader allocates only what its bytes justify.

#include "geometry/deform/articulated_mesh.h"
#include "geometry/deform/cage/cage_builder.h"
#include "geometry/deform/cage/envelope.h"
#include "geometry/deform/transfer_mesh.h"
#include "geometry/label_grid.h"
#include "geometry/organ_table.h"
#include "geometry/provenance.h"
#include "geometry/scalar_grid.h"
#include "geometry/skeleton/skeleton.h"
#include "geometry/tet_mesh.h"
#include "geometry/tri_mesh.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace vox {

class SectionFile;

inline constexpr std::uint32_t kPreparedStateVersion = 3;

// What a prepared state was made from, and what a run that takes it gives.
struct PreparedInputs {
  // Roles "grid", "grid data" (a detached data file), "organs", "parts";
  // the paths as given (messages only: the digests decide).
  std::vector<InputDigest> files;
  int workingFactor = 1;  // the working grid: the source block-downsampled by this
  Index3 workingDims{0, 0, 0};
  std::string build;  // voxmorphVersionLine() of the voxmorph that made it
};

// The inputs of a run: the SHA-256 of the grid file (input_provenance.h: a
// grid's detached data file is added as "grid data") and of the parts grid
// file ("" for none), the organ table's by its canonical text (id, name,
// tissue, density per organ: a table read from a file or built in memory
// alike), the working grid.
PreparedInputs preparedInputs(const std::string& grid, const std::optional<OrganTable>& organs, const std::string& organsSource,
                              const std::string& parts, int workingFactor, const Index3& workingDims);

struct PreparedCage {
  std::string key;          // label-group grid digest + cage options (canonical)
  std::string groups;       // the label groups it was built from, in words
  std::string separations;  // its separations, in words (world frame)
  std::string options;      // its other options, in words
  TriMesh cage;
  CageReport report;
};

struct PreparedEnvelope {
  std::string key;  // label-group grid digest + envelope options
  TriMesh envelope;
};

// The transfer mesh that resolves the skeleton (deform --articulated),
// built from the working grid, the organ table and the stored skeleton.
struct PreparedArticulatedMesh {
  std::string key;  // articulatedMeshOptionsKey
  ArticulatedMesh mesh;
};

struct PreparedTransferMesh {
  std::string key;   // group grid, label groups, sizing field digests + mesh options + cuts
  std::string cuts;  // its cuts, in words (world frame)
  TetMesh mesh;      // cut
  std::vector<CutReport> cutReports;
  std::int64_t uncoveredVoxels = 0;
};

// What a pipeline asks a prepared state for (the key and, for messages, the
// words that describe it).
struct PreparedCageQuery {
  std::string key, groups, separations, options;
};
struct PreparedMeshQuery {
  std::string key, cuts;
};

class PreparedState {
public:
  std::string source = "prepared state";  // the file, in messages
  PreparedInputs inputs;
  std::optional<skeleton::Skeleton> skeleton;
  std::vector<PreparedCage> cages;
  std::vector<PreparedEnvelope> envelopes;
  std::vector<PreparedTransferMesh> meshes;
  std::vector<PreparedArticulatedMesh> articulatedMeshes;
  // `voxmorph prepare`: pipelines add what they build. Otherwise a pipeline
  // that finds no piece for its key refuses (refuseCage, refuseMesh).
  bool recording = false;

  const PreparedCage* findCage(const std::string& key) const;
  const PreparedEnvelope* findEnvelope(const std::string& key) const;
  const PreparedTransferMesh* findMesh(const std::string& key) const;
  const PreparedArticulatedMesh* findArticulatedMesh(const std::string& key) const;
  // InputError(source, ...) naming what differs from the nearest stored
  // cage (separations, label groups, cage options) or transfer mesh (cuts).
  [[noreturn]] void refuseCage(const PreparedCageQuery& query) const;
  [[noreturn]] void refuseMesh(const PreparedMeshQuery& query) const;
  [[noreturn]] void refuseEnvelope() const;

  // A run's inputs against those it was prepared from: InputError(source,
  // "prepared from another grid ...") naming the first that differs (grid,
  // grid data, organ table, parts grid, working grid). Returns a warning
  // when only the build differs ("" otherwise).
  std::string check(const PreparedInputs& run) const;

  // Sizes and what it holds, a few lines a person reads.
  std::string summary() const;

  void write(const std::string& path) const;
  // Throws InputError(path, ...) for a file that is not a prepared state,
  // another format version, a truncated or corrupted one.
  static PreparedState read(const std::string& path);
  static PreparedState fromBytes(std::string bytes, const std::string& source);
  std::string bytes() const;

private:
  static PreparedState unpackState(const SectionFile& file);
};

// Keys: a digest of a grid's geometry and values (not cryptographic: 128
// bits of a fast hash), and the canonical text of options (doubles exactly,
// as hexadecimal floats).
std::string gridDigest(const LabelGrid& grid);
std::string gridDigest(const ScalarGrid& grid);
std::string cageOptionsKey(const CageOptions& options);
std::string envelopeOptionsKey(const EnvelopeOptions& options);
std::string transferMeshOptionsKey(const TransferMeshOptions& options);
std::string articulatedMeshOptionsKey(const ArticulatedMeshOptions& options);
std::string separationsKey(const std::vector<LimbSeparation>& separations);
// Words for messages: "right_arm:trunk@x0,y0,z0,x1,y1,z1 mm, ..." (world
// frame, as --separate takes them), "none" when empty; the cage options.
std::string separationsText(const std::vector<LimbSeparation>& separations, const GridGeometry& grid);
std::string cageOptionsText(const CageOptions& options);

}  // namespace vox
