#pragma once
// ASCII case folding and file-name suffix tests, shared by the format
// dispatchers, header parsers and name lookups; numbers as printf writes them.

#include <span>
#include <string>
#include <string_view>

namespace vox {

// ASCII lower case (bytes outside A-Z unchanged).
std::string toLowerAscii(std::string_view s);
// True when `s` ends with `suffix`, comparing without case.
bool endsWithIgnoringCase(std::string_view s, std::string_view suffix);
// The last extension of a path in lower case, dot included (".vtu"); "" when none.
std::string lowerExtension(std::string_view path);
// One number through a printf conversion for a double ("%g", "%.4g").
std::string formatNumber(const char* format, double value);
// Words as a sentence lists them: "a", "a and b", "a, b and c".
std::string joinedWords(std::span<const std::string> words);

}  // namespace vox
