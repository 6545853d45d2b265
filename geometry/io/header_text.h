#pragma once
// Reading the text headers of MetaImage, NRRD and INR files. Every parse
// failure is an InputError naming the file and the field. Internal to
// geometry/io.

#include "geometry/label_grid.h"

#include <Eigen/Core>

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

namespace vox {

std::string_view trimText(std::string_view s);
std::vector<std::string_view> splitWords(std::string_view s);

std::int64_t parseInteger(const std::string& source, const std::string& field, std::string_view text);
// A finite real number.
double parseReal(const std::string& source, const std::string& field, std::string_view text);
// Exactly `count` whitespace-separated finite reals.
std::vector<double> parseReals(const std::string& source, const std::string& field, std::string_view text, int count);
// Three whitespace-separated integers (grid dimensions; not yet range-checked).
Index3 parseDims(const std::string& source, const std::string& field, std::string_view text);

// A number as "%g" prints it, for messages.
std::string realText(double v);

// Up to `limit` bytes from the start of `file` (headers are looked for in them).
std::string readPrefix(std::FILE* file, std::size_t limit);
// The same from the file at `path` (InputError naming it when it cannot be
// opened).
std::string readFilePrefix(const std::string& path, std::size_t limit);

// The directory of `path` joined with a file name taken from its header.
std::string siblingPath(const std::string& path, const std::string& name);

}  // namespace vox
