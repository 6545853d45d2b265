#pragma once
// Shared pieces of the `voxmorph` subcommands: registration, progress on
// stderr, JSON output.

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>

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
void addPartsCommand(CLI::App& app);
void addViewCommand(CLI::App& app);

// Prints progress of long operations on stderr ("stage: 42%"), rewriting the
// line on a terminal and printing every 10% otherwise.
void installStderrProgress(bool quiet);

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

// Physical memory of the machine in MB (the default memory budget).
std::int64_t physicalMemoryMb();

// Human-readable number with thousands separators: 7161276 -> "7,161,276".
std::string withThousands(std::uint64_t n);

}  // namespace vox::app
