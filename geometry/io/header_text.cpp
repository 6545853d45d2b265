#include "geometry/io/header_text.h"

#include "geometry/error.h"
#include "geometry/io/byte_stream.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <cmath>
#include <filesystem>

namespace vox {

namespace {
bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f'; }

std::string quoted(std::string_view text) {
  std::string s(text.substr(0, 40));
  if (text.size() > 40) s += "...";
  return "\"" + s + "\"";
}
}  // namespace

std::string_view trimText(std::string_view s) {
  while (!s.empty() && isSpace(s.front())) s.remove_prefix(1);
  while (!s.empty() && isSpace(s.back())) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> splitWords(std::string_view s) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && isSpace(s[i])) ++i;
    const std::size_t start = i;
    while (i < s.size() && !isSpace(s[i])) ++i;
    if (i > start) words.push_back(s.substr(start, i - start));
  }
  return words;
}

std::int64_t parseInteger(const std::string& source, const std::string& field, std::string_view text) {
  text = trimText(text);
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  std::int64_t v = 0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  if (r.ec == std::errc::result_out_of_range) throw InputError(source, field + ": " + quoted(text) + " is out of range");
  if (r.ec != std::errc() || r.ptr != text.data() + text.size() || text.empty())
    throw InputError(source, field + ": " + quoted(text) + " is not an integer");
  return v;
}

double parseReal(const std::string& source, const std::string& field, std::string_view text) {
  text = trimText(text);
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  double v = 0.0;
  const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
  if (r.ec != std::errc() || r.ptr != text.data() + text.size() || text.empty())
    throw InputError(source, field + ": " + quoted(text) + " is not a number");
  if (!std::isfinite(v)) throw InputError(source, field + ": " + quoted(text) + " is not finite");
  return v;
}

std::vector<double> parseReals(const std::string& source, const std::string& field, std::string_view text, int count) {
  const auto words = splitWords(text);
  if (int(words.size()) != count)
    throw InputError(source, field + ": expected " + std::to_string(count) + " numbers, found " + std::to_string(words.size()));
  std::vector<double> v;
  for (const auto w : words) v.push_back(parseReal(source, field, w));
  return v;
}

Index3 parseDims(const std::string& source, const std::string& field, std::string_view text) {
  const auto words = splitWords(text);
  if (words.size() != 3)
    throw InputError(source, field + ": expected 3 dimensions, found " + std::to_string(words.size()) +
                                 " (only 3-D grids are supported)");
  return {parseInteger(source, field, words[0]), parseInteger(source, field, words[1]), parseInteger(source, field, words[2])};
}

std::string realText(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", v);
  return buf;
}

std::string readPrefix(std::FILE* file, std::size_t limit) {
  std::string s(limit, '\0');
  const std::size_t got = std::fread(s.data(), 1, limit, file);
  s.resize(got);
  return s;
}

std::string readFilePrefix(const std::string& path, std::size_t limit) {
  std::FILE* file = openForReading(path, path);
  std::string s = readPrefix(file, limit);
  std::fclose(file);
  return s;
}

std::string siblingPath(const std::string& path, const std::string& name) {
  const std::filesystem::path p(name);
  if (p.is_absolute()) return name;
  return (std::filesystem::path(path).parent_path() / p).string();
}

}  // namespace vox
