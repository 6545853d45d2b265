#include "geometry/deform/report/distortion_plot.h"

#include "geometry/bitmap_font.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace vox {

namespace {

const Rgb kPaper{255, 255, 255}, kInk{30, 30, 30}, kGrid{225, 225, 225}, kBar{52, 101, 164}, kMark{204, 0, 0};

std::string number(double v, int digits) {
  char text[32];
  std::snprintf(text, sizeof text, "%.*f", digits, v);
  return text;
}

struct Panel {
  int x0, y0, w, h;  // the plot area inside the axes
};

// Bars of `heights` over [lo, hi) in equal bins, a vertical mark at `ideal`,
// ticks every `tick` along x; heights are scaled to the tallest.
void drawHistogram(RgbImage& image, const Panel& p, const std::string& title, const std::string& xLabel, const std::string& yLabel,
                   const std::vector<double>& heights, double lo, double hi, double ideal, double tick, int tickDigits,
                   double yScale, int yDigits) {
  drawText(image, p.x0, p.y0 - 34, title, kInk);
  drawText(image, p.x0, p.y0 - 20, yLabel, kInk);
  double top = 0;
  for (const double v : heights) top = std::max(top, v);
  if (top <= 0) top = 1;
  const auto xOf = [&](double v) { return p.x0 + int(std::lround((v - lo) / (hi - lo) * double(p.w))); };
  for (int g = 1; g <= 4; ++g) {
    const int y = p.y0 + p.h - p.h * g / 4;
    fillRect(image, p.x0, y, p.x0 + p.w, y + 1, kGrid);
    const std::string label = number(top * yScale * g / 4, yDigits);
    drawText(image, p.x0 - 4 - textWidth(label), y - kGlyphHeight / 2, label, kInk);
  }
  const double bin = (hi - lo) / double(std::max<std::size_t>(1, heights.size()));
  for (std::size_t b = 0; b < heights.size(); ++b) {
    const int x0 = xOf(lo + bin * double(b)), x1 = std::max(x0 + 1, xOf(lo + bin * double(b + 1)) - (bin * p.w / (hi - lo) > 3 ? 1 : 0));
    const int height = int(std::lround(heights[b] / top * double(p.h)));
    fillRect(image, x0, p.y0 + p.h - height, x1, p.y0 + p.h, kBar);
  }
  const int xi = xOf(ideal);
  fillRect(image, xi, p.y0, xi + 1, p.y0 + p.h, kMark);
  fillRect(image, p.x0, p.y0 + p.h, p.x0 + p.w + 1, p.y0 + p.h + 1, kInk);
  fillRect(image, p.x0, p.y0, p.x0 + 1, p.y0 + p.h, kInk);
  for (double t = std::ceil(lo / tick) * tick; t <= hi + 1e-9; t += tick) {
    const int x = xOf(t);
    fillRect(image, x, p.y0 + p.h, x + 1, p.y0 + p.h + 4, kInk);
    const std::string label = number(t, tickDigits);
    drawText(image, x - textWidth(label) / 2, p.y0 + p.h + 6, label, kInk);
  }
  drawText(image, p.x0 + p.w / 2 - textWidth(xLabel) / 2, p.y0 + p.h + 20, xLabel, kInk);
}

}  // namespace

RgbImage distortionPlot(const DeformationReport& r) {
  constexpr int kPanelWidth = 360, kPanelHeight = 220, kLeft = 56, kTop = 60;
  RgbImage image(3 * (kPanelWidth + kLeft) + 64, kTop + kPanelHeight + 70, kPaper);
  const DistortionHistogram& angle = r.distortion.angle;
  const DistortionHistogram& stretch = r.distortion.stretch;
  drawHistogram(image, {kLeft, kTop, kPanelWidth, kPanelHeight},
                "Angle between mapped orthogonal edges (mean " + number(angle.mean, 2) + ", range " + number(angle.min, 1) + "-" +
                    number(angle.max, 1) + ")",
                "angle (degrees); red: undistorted", "% of volume", angle.fractions, angle.lo, angle.hi, 90.0, 15.0, 0, 100.0, 1);
  drawHistogram(image, {2 * kLeft + kPanelWidth + 12, kTop, kPanelWidth, kPanelHeight},
                "Stretch of unit edges (mean " + number(stretch.mean, 3) + ", range " + number(stretch.min, 2) + "-" +
                    number(stretch.max, 2) + ")",
                "length ratio; red: undistorted", "% of volume", stretch.fractions, stretch.lo, stretch.hi, 1.0, 0.25, 2, 100.0, 1);
  const int bins = int(std::lround(4 * kPlotChangeRange));
  std::vector<double> counts(std::size_t(bins), 0.0);
  std::size_t organs = 0;
  for (const LabelChange& c : r.labels) {
    if (c.before < kSmallOrganVoxels) continue;
    const double f = (c.volumeChangePercent + kPlotChangeRange) / (2 * kPlotChangeRange);
    counts[std::size_t(std::clamp(int(std::floor(f * bins)), 0, bins - 1))] += 1;
    ++organs;
  }
  drawHistogram(image, {3 * kLeft + 2 * kPanelWidth + 24, kTop, kPanelWidth, kPanelHeight},
                "Organ volume change (" + std::to_string(organs) + " organs >= " + std::to_string(kSmallOrganVoxels) + " voxels)",
                "change (%), ends hold what lies beyond", "organs", counts, -kPlotChangeRange, kPlotChangeRange, 0.0, 2.5, 1, 1.0, 1);
  drawText(image, kLeft, 8, r.input + " posed by " + r.pose, kInk);
  drawText(image, kLeft, image.height - 16,
           "Angles and stretch measured on the transfer-mesh tets, weighted by rest volume (" +
               number(100.0 * (stretch.below + stretch.above), 2) + " % of the volume outside the stretch axis)",
           kInk);
  return image;
}

}  // namespace vox
