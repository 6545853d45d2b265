#pragma once
// Organ table: label -> organ name, tissue (media) number, density (g/cm^3).
// Format of the ICRP 110 "organs.dat" files (../assets/icrp110_*_organs.dat):
// header lines, then one line per organ "ID  name words...  tissue  density".
// Lines that do not start with an integer are skipped; CRLF is accepted.

#include "geometry/label_grid.h"

#include <cstdint>
#include <initializer_list>
#include <map>
#include <string>
#include <vector>

namespace vox {

struct Organ {
  int id = 0;
  std::string name;
  int tissue = 0;
  double density = 1.0;  // g/cm^3
};

class OrganTable;

// The lowercase alphabetic words of an organ name ("Humeri, upper half,
// cortical" -> humeri, upper, half, cortical): what name classifications
// (label groups, bones) match.
std::vector<std::string> organNameWords(const std::string& name);
// True when a word starts with one of the prefixes.
bool anyWordStartsWith(const std::vector<std::string>& words, std::initializer_list<const char*> prefixes);

// "labels without a name in the organ table: 141 (3,880 voxels); their mass
// is left out of the totals", or "" when every label has a name.
std::string unnamedLabelsNote(const OrganTable& organs, const std::vector<std::uint64_t>& counts);

class OrganTable {
public:
  // Throws InputError(path, ...) for unreadable files, malformed organ lines,
  // duplicate IDs, IDs outside 1..65535, or non-positive densities.
  static OrganTable read(const std::string& path);

  const Organ* find(int id) const;
  const std::map<int, Organ>& organs() const { return organs_; }
  bool empty() const { return organs_.empty(); }
  // Mass in grams of `voxels` voxels of organ `id` with voxel volume in mm^3;
  // 0 when the organ is unknown.
  double mass(int id, std::uint64_t voxels, double voxelVolumeMm3) const;
  // IDs whose names contain any of the given substrings (case-insensitive).
  std::vector<int> idsMatching(const std::vector<std::string>& substrings) const;
  // Labels > 0 with voxels (counts indexed by label) that the table does not
  // name: their mass is unknown and left out of every total.
  std::vector<int> unnamedLabels(const std::vector<std::uint64_t>& counts) const;

  void add(Organ organ) { organs_[organ.id] = std::move(organ); }
  // Writes the table in the format read() accepts (atomic).
  void write(const std::string& path) const;

private:
  std::map<int, Organ> organs_;
};

}  // namespace vox
