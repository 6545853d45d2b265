#pragma once
// The PNG of `voxmorph deform --plots`: the distortion histograms of the
// thesis' Figure 3.19 (angles between the images of orthogonal dual edges,
// stretch of unit dual edges, both as a share of the measured volume) beside
// the histogram of the organs' volume changes.

#include "geometry/deform/report/deformation_report.h"
#include "geometry/rgb_image.h"

namespace vox {

// Organs' volume changes are binned 0.5 % wide over [-kPlotChangeRange,
// kPlotChangeRange]; changes beyond are counted in the end bins.
inline constexpr double kPlotChangeRange = 10.0;

RgbImage distortionPlot(const DeformationReport& report);

}  // namespace vox
