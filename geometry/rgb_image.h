#pragma once
// 8-bit RGB images (rendered frames, golden images) and their comparison.

#include <cstdint>
#include <vector>

namespace vox {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb&) const = default;
};

struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<Rgb> pixels;  // width * height, row 0 at the top, x fastest

  RgbImage() = default;
  RgbImage(int w, int h, Rgb fill = {}) : width(w), height(h), pixels(std::size_t(w) * std::size_t(h), fill) {}
  Rgb& at(int x, int y) { return pixels[std::size_t(y) * std::size_t(width) + std::size_t(x)]; }
  const Rgb& at(int x, int y) const { return pixels[std::size_t(y) * std::size_t(width) + std::size_t(x)]; }
};

struct ImageDifference {
  std::size_t pixels = 0;    // pixels compared
  std::size_t differing = 0; // pixels with a channel off by more than the threshold
  int maxChannelDifference = 0;
  double differingFraction() const { return pixels ? double(differing) / double(pixels) : 0.0; }
};

// Per-pixel comparison; a pixel differs when any channel differs by more than
// `threshold` (out of 255). Throws RuntimeFailure when the sizes differ.
ImageDifference compareImages(const RgbImage& a, const RgbImage& b, int threshold);

// Pixels whose colour differs from `background`.
std::size_t countNotBackground(const RgbImage& image, Rgb background);

}  // namespace vox
