#include "geometry/render/image_annotations.h"

#include "geometry/bitmap_font.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace vox {

namespace {

const Rgb kText{235, 235, 235}, kShadow{0, 0, 0};

void drawLabel(RgbImage& image, int x, int y, const std::string& text) {
  drawText(image, x + 1, y + 1, text, kShadow);
  drawText(image, x, y, text, kText);
}

}  // namespace

void drawLegend(RgbImage& image, const std::vector<LegendEntry>& entries) {
  constexpr int kRow = kGlyphHeight + 4, kMargin = 8, kSwatch = 10, kMaxName = 32;
  const int fit = std::max(1, (image.height - 2 * kMargin) / kRow);
  const std::size_t shown = entries.size() <= std::size_t(fit) ? entries.size() : std::size_t(fit - 1);
  for (std::size_t k = 0; k < shown; ++k) {
    const int y = kMargin + int(k) * kRow;
    fillRect(image, kMargin - 1, y - 1, kMargin + kSwatch + 1, y + kSwatch + 1, kShadow);
    fillRect(image, kMargin, y, kMargin + kSwatch, y + kSwatch, entries[k].color);
    drawLabel(image, kMargin + kSwatch + 5, y, entries[k].name.substr(0, kMaxName));
  }
  if (shown < entries.size())
    drawLabel(image, kMargin, kMargin + int(shown) * kRow, "+ " + std::to_string(entries.size() - shown) + " more");
}

double drawScaleBar(RgbImage& image, const CameraRays& camera, double targetDepthMm) {
  const double mmPerPixel = 2.0 * targetDepthMm * camera.tanHalfFovY / double(image.height);
  const double wanted = 0.2 * double(image.width) * mmPerPixel;
  const double decade = std::pow(10.0, std::floor(std::log10(wanted)));
  double length = decade;
  for (const double f : {2.0, 5.0})
    if (f * decade <= wanted) length = f * decade;
  const int pixels = std::max(1, int(std::lround(length / mmPerPixel)));
  const int x1 = image.width - 12, x0 = x1 - pixels, y = image.height - 14;
  fillRect(image, x0 - 1, y - 1, x1 + 1, y + 4, kShadow);
  fillRect(image, x0, y, x1, y + 3, kText);
  fillRect(image, x0, y - 5, x0 + 2, y + 3, kText);
  fillRect(image, x1 - 2, y - 5, x1, y + 3, kText);
  char text[32];
  std::snprintf(text, sizeof text, "%g mm", length);
  drawLabel(image, x0 + pixels / 2 - textWidth(text) / 2, y - 5 - kGlyphHeight - 2, text);
  return length;
}

}  // namespace vox
