#include "geometry/rgb_image.h"

#include "geometry/error.h"

#include <algorithm>
#include <cstdlib>
#include <string>

namespace vox {

ImageDifference compareImages(const RgbImage& a, const RgbImage& b, int threshold) {
  if (a.width != b.width || a.height != b.height)
    throw RuntimeFailure("images of different sizes compared: " + std::to_string(a.width) + "x" + std::to_string(a.height) +
                         " and " + std::to_string(b.width) + "x" + std::to_string(b.height));
  ImageDifference d;
  d.pixels = a.pixels.size();
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    const Rgb& p = a.pixels[i];
    const Rgb& q = b.pixels[i];
    const int m = std::max({std::abs(int(p.r) - int(q.r)), std::abs(int(p.g) - int(q.g)), std::abs(int(p.b) - int(q.b))});
    d.maxChannelDifference = std::max(d.maxChannelDifference, m);
    d.differing += m > threshold;
  }
  return d;
}

std::size_t countNotBackground(const RgbImage& image, Rgb background) {
  return std::size_t(std::count_if(image.pixels.begin(), image.pixels.end(), [&](const Rgb& p) { return !(p == background); }));
}

}  // namespace vox
