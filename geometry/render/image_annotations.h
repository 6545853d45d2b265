#pragma once
// What `voxmorph render` draws over the ray-cast image: a legend of the
// visible organs with their colours, and a scale bar.

#include "geometry/render/camera.h"
#include "geometry/rgb_image.h"

#include <string>
#include <vector>

namespace vox {

struct LegendEntry {
  Rgb color;
  std::string name;
};

// Swatches and names in a column at the top left, as many as fit the image's
// height (the rest summed up in a last line "+ N more").
void drawLegend(RgbImage& image, const std::vector<LegendEntry>& entries);

// A bar of a round length (1, 2 or 5 times a power of ten mm) about a fifth
// of the image wide, at the bottom right, measured at the depth of the
// camera's target; returns its length in mm.
double drawScaleBar(RgbImage& image, const CameraRays& camera, double targetDepthMm);

}  // namespace vox
