#pragma once
// Shared pieces of the `voxmorph` subcommands: registration, progress on
// stderr, JSON output.

#include "geometry/provenance.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace vox {
struct LimbSeparation;
}

namespace vox::app {

// Each subcommand adds itself to the application (one file per command).
void addInfoCommand(CLI::App& app);
void addSynthCommand(CLI::App& app);
void addMeshCommand(CLI::App& app);
void addRemeshCommand(CLI::App& app);
void addRenderCommand(CLI::App& app);
void addCageCommand(CLI::App& app);
void addDeformCommand(CLI::App& app);
void addPrepareCommand(CLI::App& app);
void addPartsCommand(CLI::App& app);
void addViewCommand(CLI::App& app);

// Prints progress of long operations on stderr ("stage: 42%"), rewriting the
// line on a terminal and printing every 10% otherwise.
void installStderrProgress(bool quiet);

// Memory a stage frees stays with the allocator for the next (deform,
// prepare, view): their stages each take grids and lattice states of a few
// to tens of MB, which would otherwise go back to the kernel and return page
// by page, one page fault each (docs/BENCHMARKS.md, "Page faults"). Not for
// mesh and remesh, whose peak memory it raised (1.52 to 1.67 GB on the AM).
void retainFreedMemory();

// The subcommands allocate grids, lattice states and meshes of tens to
// hundreds of MB, and fault them in 4 KiB page by page. Where the kernel
// gives transparent huge pages on request (`madvise` mode), the process is
// started again once with glibc's malloc asking for them
// (GLIBC_TUNABLES=glibc.malloc.hugetlb=1, glibc 2.35 on); the same bytes come
// out (docs/BENCHMARKS.md, "Huge pages"). VOXMORPH_SMALL_PAGES=1 turns it off.
// Returns only when the process is not started again.
void useHugePages(int argc, char** argv);

// A subcommand whose first argument is a label grid (any format the readers
// know), required, into `grid`.
CLI::App* addGridSubcommand(CLI::App& app, const std::string& name, const std::string& description, std::string& grid);

// The command line of this process, shell-quoted; main records it before
// parsing.
void recordCommandLine(int argc, const char* const* argv);
const std::string& recordedCommandLine();
// Provenance of this command (provenance.h): version, command line and the
// SHA-256 of the input files given as (role, path), empty paths skipped.
Provenance commandProvenance(const std::vector<std::pair<std::string, std::string>>& files);

// Writes `json` (indented) atomically to `path`, or to stdout for "-".
void writeJson(const std::string& path, const nlohmann::json& json);

// --separate GROUP:GROUP[@xmin,ymin,zmin,xmax,ymax,zmax] (cage and deform
// commands). Throws InputError naming the option for bad syntax or groups.
LimbSeparation parseSeparation(const std::string& text);
// The warning for a cage that leaves foreground voxels outside although no
// limb separation asked for it (cage and deform commands).
void warnForegroundOutside(std::int64_t voxels, bool separated);

// One style of range message for every numeric option, NaN and infinities
// refused: "--length: must be a number in (0, 100000] mm, got 'nan'". A lower
// bound given as open excludes it (a length must be > 0).
CLI::Validator numberIn(double lo, double hi, const std::string& unit, bool openLow = false);
CLI::Validator integerIn(std::int64_t lo, std::int64_t hi, const std::string& unit = "");

// The default memory budget in MB: the machine's physical memory, or less
// where the process is capped (address-space limit, ulimit -v; cgroup v2
// memory.max).
std::int64_t physicalMemoryMb();

// In-core work per voxel of the commands that hold a whole grid, with
// margin over the peak RSS per voxel measured on the ICRP 110 phantoms
// (docs/RELIABILITY.md, "Memory").
struct GridMemoryCost {
  double bytesPerVoxel;
  std::int64_t fixedMb;
};
inline constexpr GridMemoryCost kCageMemory{40.0, 64};
inline constexpr GridMemoryCost kRenderMemory{24.0, 128};
inline constexpr GridMemoryCost kPosedMemory{64.0, 256};   // render --pose, view: cage, TM, Green coordinates
inline constexpr GridMemoryCost kDeformMemory{128.0, 128};  // deform in core (without --max-memory)
inline constexpr GridMemoryCost kMeshGridMemory{4.0, 0};  // mesh: the grid, before the meshing estimate (which has the rest)

// Refuses, from the header alone and before `path` is read, a grid whose
// in-core work needs more than the budget (`maxMemoryMb`, or
// physicalMemoryMb() when 0): `cost` per voxel plus its fixed part.
// Throws InputError(path, "... voxels need about N MB to <work>, over the
// M MB budget; <hint>"), exit 1. Returns the estimate in MB.
std::int64_t checkGridFitsMemory(const std::string& path, std::int64_t maxMemoryMb, GridMemoryCost cost, const std::string& work,
                                 const std::string& hint);

// Human-readable number with thousands separators: 7161276 -> "7,161,276".
std::string withThousands(std::uint64_t n);

}  // namespace vox::app
