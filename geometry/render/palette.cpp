#include "geometry/ascii_text.h"
#include "geometry/render/palette.h"

#include "geometry/error.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>

namespace vox {

namespace {

Rgb fromFloat(double r, double g, double b) {
  auto q = [](double v) { return std::uint8_t(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); };
  return {q(r), q(g), q(b)};
}

std::uint32_t mix(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7FEB352Du;
  x ^= x >> 15;
  x *= 0x846CA68Bu;
  x ^= x >> 16;
  return x;
}

Rgb hsv(double h, double s, double v) {
  h = (h - std::floor(h)) * 6.0;
  const int i = int(h) % 6;
  const double f = h - std::floor(h);
  const double p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  switch (i) {
    case 0: return fromFloat(v, t, p);
    case 1: return fromFloat(q, v, p);
    case 2: return fromFloat(p, v, t);
    case 3: return fromFloat(p, q, v);
    case 4: return fromFloat(t, p, v);
    default: return fromFloat(v, p, q);
  }
}

struct NamedColor {
  const char* word;  // lower-case substring of an organ name
  double r, g, b;
};
// First match wins, so specific words come before general ones.
constexpr std::array kNamedColors = {
    NamedColor{"skin", 0.89, 0.70, 0.60},       NamedColor{"medullary", 0.93, 0.80, 0.35},
    NamedColor{"spongiosa", 0.90, 0.84, 0.68},  NamedColor{"cartilage", 0.72, 0.84, 0.90},
    NamedColor{"teeth", 0.98, 0.98, 0.92},      NamedColor{"cortical", 0.95, 0.93, 0.85},
    NamedColor{"bone", 0.95, 0.93, 0.85},       NamedColor{"lung", 0.95, 0.62, 0.68},
    NamedColor{"heart", 0.62, 0.08, 0.10},      NamedColor{"blood", 0.55, 0.04, 0.08},
    NamedColor{"arter", 0.70, 0.06, 0.06},      NamedColor{"vein", 0.25, 0.10, 0.45},
    NamedColor{"brain", 0.86, 0.78, 0.76},      NamedColor{"liver", 0.52, 0.20, 0.13},
    NamedColor{"kidney", 0.62, 0.24, 0.20},     NamedColor{"spleen", 0.45, 0.10, 0.22},
    NamedColor{"stomach", 0.88, 0.56, 0.46},    NamedColor{"colon", 0.82, 0.62, 0.44},
    NamedColor{"intestine", 0.86, 0.60, 0.50},  NamedColor{"oesophagus", 0.85, 0.50, 0.45},
    NamedColor{"bladder", 0.90, 0.82, 0.40},    NamedColor{"pancreas", 0.92, 0.72, 0.50},
    NamedColor{"thyroid", 0.72, 0.30, 0.38},    NamedColor{"lymph", 0.50, 0.72, 0.40},
    NamedColor{"eye", 0.92, 0.92, 0.96},        NamedColor{"lens", 0.80, 0.90, 1.00},
    NamedColor{"adipose", 0.96, 0.86, 0.52},    NamedColor{"fat", 0.96, 0.86, 0.52},
    NamedColor{"muscle", 0.72, 0.24, 0.22},     NamedColor{"air", 0.80, 0.90, 0.95},
    NamedColor{"nasal", 0.84, 0.66, 0.66},      NamedColor{"trachea", 0.80, 0.70, 0.74},
    NamedColor{"bronchi", 0.80, 0.70, 0.74},    NamedColor{"residual", 0.86, 0.74, 0.58},
    NamedColor{"rectum", 0.82, 0.62, 0.44},     NamedColor{"spinal cord", 0.96, 0.90, 0.62},
    NamedColor{"tongue", 0.84, 0.42, 0.48},     NamedColor{"mucosa", 0.84, 0.42, 0.48},
    NamedColor{"breast", 0.96, 0.80, 0.74},     NamedColor{"adrenal", 0.90, 0.64, 0.30},
    NamedColor{"ureter", 0.90, 0.82, 0.40},     NamedColor{"gland", 0.80, 0.58, 0.70},
    NamedColor{"thymus", 0.80, 0.58, 0.70},     NamedColor{"tonsil", 0.80, 0.58, 0.70},
    NamedColor{"prostate", 0.78, 0.48, 0.60},   NamedColor{"testis", 0.78, 0.48, 0.60},
    NamedColor{"ovary", 0.78, 0.48, 0.60},      NamedColor{"uterus", 0.78, 0.48, 0.60},
};


}  // namespace

Rgb defaultLabelColor(Label l) {
  // Golden-ratio hue steps keep consecutive labels apart; the hash varies
  // saturation and value a little so labels far apart differ too.
  const std::uint32_t h = mix(std::uint32_t(l) + 0x9E3779B9u);
  const double hue = std::fmod(double(l) * 0.6180339887498949, 1.0);
  const double sat = 0.45 + 0.35 * double(h & 0xFF) / 255.0;
  const double val = 0.70 + 0.28 * double((h >> 8) & 0xFF) / 255.0;
  return hsv(hue, sat, val);
}

Palette::Palette(Label maxLabel) : colors_(std::size_t(maxLabel) + 1), visible_(std::size_t(maxLabel) + 1, 1) {
  for (std::size_t l = 0; l < colors_.size(); ++l) colors_[l] = defaultLabelColor(Label(l));
  visible_[0] = 0;
}

Palette Palette::fromOrgans(const OrganTable& organs, Label maxLabel) {
  Palette p(maxLabel);
  for (const auto& [id, organ] : organs.organs()) {
    if (id < 1 || id > int(maxLabel)) continue;
    const std::string name = toLowerAscii(organ.name);
    for (const NamedColor& c : kNamedColors) {
      if (name.find(c.word) == std::string::npos) continue;
      // Organs sharing a colour word differ slightly in brightness, so
      // neighbouring bones or muscles stay distinguishable.
      const double shade = 0.92 + 0.16 * double(mix(std::uint32_t(id)) & 0xFF) / 255.0;
      p.colors_[std::size_t(id)] = fromFloat(c.r * shade, c.g * shade, c.b * shade);
      break;
    }
  }
  return p;
}

void Palette::hide(const std::string& list, const OrganTable* organs) {
  std::size_t start = 0;
  while (start <= list.size()) {
    std::size_t comma = list.find(',', start);
    if (comma == std::string::npos) comma = list.size();
    std::string item = list.substr(start, comma - start);
    start = comma + 1;
    while (!item.empty() && item.front() == ' ') item.erase(item.begin());
    while (!item.empty() && item.back() == ' ') item.pop_back();
    if (item.empty()) throw UsageError("--hide", "empty item in '" + list + "'");
    const bool numeric = std::isdigit(static_cast<unsigned char>(item[0])) != 0;
    if (numeric) {
      long lo = 0, hi = 0;
      const char* end = item.data() + item.size();
      auto r = std::from_chars(item.data(), end, lo);
      hi = lo;
      if (r.ec == std::errc() && r.ptr != end && *r.ptr == '-') r = std::from_chars(r.ptr + 1, end, hi);
      if (r.ec != std::errc() || r.ptr != end || lo < 0 || hi < lo)
        throw UsageError("--hide", "'" + item + "' is not a label or a range LOW-HIGH");
      if (hi >= long(colors_.size()))
        throw UsageError("--hide", "label " + std::to_string(hi) + " is above the grid's largest label " + std::to_string(colors_.size() - 1));
      for (long l = lo; l <= hi; ++l) visible_[std::size_t(l)] = 0;
      continue;
    }
    if (!organs) throw UsageError("--hide", "'" + item + "' is not a label number (organ names need --organs)");
    const std::vector<int> ids = organs->idsMatching({item});
    bool any = false;
    for (int id : ids)
      if (id >= 0 && std::size_t(id) < visible_.size()) {
        visible_[std::size_t(id)] = 0;
        any = true;
      }
    if (!any) throw UsageError("--hide", "no organ of the grid matches '" + item + "'");
  }
}

}  // namespace vox
