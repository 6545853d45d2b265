#pragma once
// Label grid formats: NIfTI-1 (.nii, .nii.gz), MetaImage (.mha, .mhd + raw,
// optionally zlib-compressed), NRRD (.nrrd, .nhdr; raw or gzip), INR (.inr,
// .inr.gz). Format is chosen by extension.
//
// Readers accept integer voxel types (and float types holding integers) and
// widen to uint16; anything else is an InputError naming the file and the
// fault. Writers are atomic (AtomicFile) and store uint8 when every label fits,
// uint16 otherwise.

#include "geometry/grid_slices.h"
#include "geometry/label_grid.h"

#include <cstdint>
#include <memory>
#include <string>

namespace vox {

enum class GridFormat { Nifti, MetaImage, Nrrd, Inr };

// Throws InputError(path, "unknown grid format ...") for other extensions.
GridFormat gridFormatFromPath(const std::string& path);
bool hasGridExtension(const std::string& path);

LabelGrid readGrid(const std::string& path);
void writeGrid(const std::string& path, const LabelGrid& grid);

// Per-format entry points (what readGrid / writeGrid dispatch to).
LabelGrid readNifti(const std::string& path);
void writeNifti(const std::string& path, const LabelGrid& grid);
LabelGrid readMetaImage(const std::string& path);
void writeMetaImage(const std::string& path, const LabelGrid& grid);
LabelGrid readNrrd(const std::string& path);
void writeNrrd(const std::string& path, const LabelGrid& grid);
LabelGrid readInr(const std::string& path);
void writeInr(const std::string& path, const LabelGrid& grid);

// Supported for every grid format; compressed files read backwards restart
// from the beginning (slow), so read them forwards.
std::unique_ptr<GridSliceReader> openGridSlices(const std::string& path);
// Whether openGridSlices(path) reads slices in any order at no extra cost:
// only an uncompressed NIfTI is sure to seek cheaply.
bool gridSlicesSeekable(const std::string& path);

// Supported for every grid format (.mha stores its data uncompressed when
// streamed). `maxLabel` decides the stored type (uint8 when <= 255).
std::unique_ptr<GridSliceWriter> createGridSlices(const std::string& path, const GridGeometry& geometry, Label maxLabel);

}  // namespace vox
