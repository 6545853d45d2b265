#pragma once
// PNG images through libpng: 8-bit RGB out, any PNG in (converted to 8-bit RGB).

#include "geometry/rgb_image.h"

#include <string>

namespace vox {

// Atomic (AtomicFile): a failure never leaves a partial file at `path`.
// Throws RuntimeFailure naming the path on I/O or encoder errors.
void writePng(const std::string& path, const RgbImage& image);

// Palette, grey, 16-bit and alpha images are converted to 8-bit RGB (alpha is
// dropped). Throws InputError(path, ...) for unreadable or corrupt files.
RgbImage readPng(const std::string& path);

}  // namespace vox
