#pragma once
// Text and filled rectangles on RgbImage, for the legends, scale bars and
// plots that voxmorph draws into its PNGs: the 6 x 10 "fixed" X11 bitmap
// font (public domain), printable ASCII, scaled by whole pixels.

#include "geometry/rgb_image.h"

#include <string_view>

namespace vox {

inline constexpr int kGlyphWidth = 6;
inline constexpr int kGlyphHeight = 10;

// Draws `text` with its top-left corner at (x, y); characters outside
// printable ASCII show as '?'. Pixels outside the image are clipped.
void drawText(RgbImage& image, int x, int y, std::string_view text, Rgb color, int scale = 1);
int textWidth(std::string_view text, int scale = 1);

// Fills [x0, x1) x [y0, y1), clipped to the image.
void fillRect(RgbImage& image, int x0, int y0, int x1, int y1, Rgb color);

}  // namespace vox
