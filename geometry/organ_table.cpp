#include "geometry/organ_table.h"

#include "geometry/ascii_text.h"
#include "geometry/error.h"
#include "geometry/atomic_file.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace vox {

std::vector<std::string> organNameWords(const std::string& name) {
  std::vector<std::string> words;
  std::string w;
  for (const unsigned char c : name) {
    if (std::isalpha(c)) {
      w += char(std::tolower(c));
    } else if (!w.empty()) {
      words.push_back(std::move(w));
      w.clear();
    }
  }
  if (!w.empty()) words.push_back(std::move(w));
  return words;
}

bool anyWordStartsWith(const std::vector<std::string>& words, std::initializer_list<const char*> prefixes) {
  for (const std::string& w : words)
    for (const char* p : prefixes)
      if (w.rfind(p, 0) == 0) return true;
  return false;
}

std::vector<int> OrganTable::unnamedLabels(const std::vector<std::uint64_t>& counts) const {
  std::vector<int> unnamed;
  for (std::size_t l = 1; l < counts.size(); ++l)
    if (counts[l] > 0 && !find(int(l))) unnamed.push_back(int(l));
  return unnamed;
}

std::string unnamedLabelsNote(const OrganTable& organs, const std::vector<std::uint64_t>& counts) {
  const std::vector<int> unnamed = organs.unnamedLabels(counts);
  if (unnamed.empty()) return "";
  std::string text = "labels without a name in the organ table:";
  for (std::size_t k = 0; k < unnamed.size(); ++k) {
    std::string voxels = std::to_string(counts[std::size_t(unnamed[k])]);
    for (int i = int(voxels.size()) - 3; i > 0; i -= 3) voxels.insert(std::size_t(i), ",");
    text += (k ? ", " : " ") + std::to_string(unnamed[k]) + " (" + voxels + " voxels)";
  }
  return text + "; their mass is left out of the totals";
}

OrganTable OrganTable::read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open organ table");
  OrganTable table;
  std::string line;
  int lineNo = 0;
  while (std::getline(in, line)) {
    ++lineNo;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ss(line);
    std::vector<std::string> tok;
    for (std::string t; ss >> t;) tok.push_back(t);
    if (tok.empty() || !std::all_of(tok[0].begin(), tok[0].end(), [](unsigned char c) { return std::isdigit(c); })) continue;
    const std::string where = "line " + std::to_string(lineNo);
    if (tok.size() < 4) throw InputError(path, where + ": expected 'ID name tissue density'");
    Organ o;
    try {
      std::size_t used = 0;
      const long id = std::stol(tok[0]);
      o.tissue = std::stoi(tok[tok.size() - 2], &used);
      if (used != tok[tok.size() - 2].size()) throw std::invalid_argument("tissue");
      o.density = std::stod(tok.back(), &used);
      if (used != tok.back().size()) throw std::invalid_argument("density");
      if (id < 1 || id > 65535) throw InputError(path, where + ": organ ID " + tok[0] + " is outside 1..65535");
      o.id = int(id);
    } catch (const std::logic_error&) {
      throw InputError(path, where + ": expected 'ID name tissue density'");
    }
    if (!std::isfinite(o.density) || o.density <= 0.0) throw InputError(path, where + ": density must be positive");
    for (std::size_t t = 1; t + 2 < tok.size(); ++t) o.name += (t > 1 ? " " : "") + tok[t];
    if (table.organs_.count(o.id)) throw InputError(path, where + ": duplicate organ ID " + std::to_string(o.id));
    table.organs_[o.id] = std::move(o);
  }
  if (in.bad()) throw InputError(path, "read error");
  if (table.organs_.empty()) throw InputError(path, "no organ lines found (expected 'ID name tissue density')");
  return table;
}

const Organ* OrganTable::find(int id) const {
  const auto it = organs_.find(id);
  return it == organs_.end() ? nullptr : &it->second;
}

double OrganTable::mass(int id, std::uint64_t voxels, double voxelVolumeMm3) const {
  const Organ* o = find(id);
  // mm^3 -> cm^3 is 1e-3; density in g/cm^3.
  return o ? double(voxels) * voxelVolumeMm3 * 1e-3 * o->density : 0.0;
}

std::vector<int> OrganTable::idsMatching(const std::vector<std::string>& substrings) const {
  std::vector<int> ids;
  for (const auto& [id, o] : organs_) {
    const std::string n = toLowerAscii(o.name);
    for (const auto& s : substrings)
      if (n.find(toLowerAscii(s)) != std::string::npos) {
        ids.push_back(id);
        break;
      }
  }
  return ids;
}

void OrganTable::write(const std::string& path) const {
  std::string out = "Organ table\n\nOrgan Organ                                          Tissue Density\nID                                                   number\n";
  char line[256];
  for (const auto& [id, o] : organs_) {
    std::snprintf(line, sizeof line, "%-5d %-48s %5d %8.3f\n", id, o.name.c_str(), o.tissue, o.density);
    out += line;
  }
  writeFileAtomic(path, out);
}

}  // namespace vox
