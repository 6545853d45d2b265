#pragma once
// Label colours and per-label visibility for the ray caster.

#include "geometry/label_grid.h"
#include "geometry/organ_table.h"
#include "geometry/rgb_image.h"

#include <string>
#include <vector>

namespace vox {

class Palette {
public:
  // Colours for labels 0..maxLabel from the default palette (well separated
  // hues, the same for a label in every run). Label 0 is background: hidden.
  explicit Palette(Label maxLabel = 0);
  // Colours chosen from the organ names (skin, bone, muscle, lung, fat,
  // blood...), with the default palette for names it does not know; labels
  // the table lacks keep their default colour.
  static Palette fromOrgans(const OrganTable& organs, Label maxLabel);

  std::size_t size() const { return colors_.size(); }  // maxLabel + 1
  Rgb color(Label l) const { return colors_[l]; }
  bool visible(Label l) const { return visible_[l] != 0; }
  void setColor(Label l, Rgb c) { colors_[l] = c; }
  void setVisible(Label l, bool v) { visible_[l] = l != 0 && v; }

  // Hides labels given as "5,7,10-20", or as organ-name substrings when an
  // organ table is given ("skin,adipose"). Throws InputError("--hide", ...) for
  // malformed lists, labels above maxLabel, or names that match nothing.
  void hide(const std::string& list, const OrganTable* organs = nullptr);

private:
  std::vector<Rgb> colors_;
  std::vector<std::uint8_t> visible_;
};

// The default colour of a label.
Rgb defaultLabelColor(Label l);

}  // namespace vox
