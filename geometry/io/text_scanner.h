#pragma once
// Internal to geometry/io: whole-file input, a whitespace tokenizer with line
// numbers for the text mesh formats (Medit, Gmsh, OBJ, OFF, VTU ascii arrays),
// and a buffered number formatter for their writers.
//
// Numbers are parsed with std::from_chars and written with std::to_chars
// (shortest representation that reads back to the same double), so a write ->
// read round trip reproduces every coordinate bit for bit.

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

namespace vox::io {

// The whole file as bytes. Throws InputError(path, ...) when it cannot be read.
std::string readWholeFile(const std::string& path);

class TextScanner {
public:
  // `path` (for error messages) must outlive the scanner. `comment` starts a
  // comment running to the end of the line ('\0': none);
  // `firstLine` is the line number of the first byte of `text` in the file.
  TextScanner(std::string_view text, const std::string& path, char comment = '\0', std::size_t firstLine = 1);

  // Skips whitespace and comments; returns false at the end of the input.
  bool skipSpace();
  bool atEnd() { return !skipSpace(); }
  // Next whitespace-delimited token; empty at the end of the input.
  std::string_view word();
  // The next token without consuming it.
  std::string_view peekWord();
  // The next token as a number; throws InputError naming the line and `what`
  // when the token is missing or is not a number of that kind.
  std::int64_t integer(std::string_view what);
  double real(std::string_view what);  // finite values only
  // A non-negative item count that the rest of the file can hold, given that
  // one item takes at least `minBytesPerItem` bytes: a corrupt count fails here
  // instead of asking for terabytes.
  std::size_t count(std::string_view what, std::size_t minBytesPerItem);

  // Rest of the current line (without the newline); moves to the next line.
  std::string_view restOfLine();
  void skipLine() { restOfLine(); }

  std::size_t line() const { return line_; }
  std::size_t position() const { return pos_; }
  // Moves to an absolute offset (binary sections); line numbers stop being
  // meaningful past binary data, so callers name blocks instead.
  void seek(std::size_t pos) { pos_ = pos < text_.size() ? pos : text_.size(); }
  // Moves forward to `pos` in text, counting the lines passed.
  void advanceTo(std::size_t pos);
  std::size_t remainingBytes() const { return text_.size() - pos_; }
  std::string_view text() const { return text_; }
  const std::string& path() const { return path_; }

  // Throws InputError(path, "line N: <fault>").
  [[noreturn]] void fail(const std::string& fault) const;

private:
  std::string_view text_;
  const std::string& path_;
  char comment_;
  std::size_t pos_ = 0;
  std::size_t line_ = 1;
};

// Quotes a token for an error message, shortened when long.
std::string quoted(std::string_view token);

// Buffered text output onto a stdio stream (an AtomicFile's temporary).
// Write errors surface in AtomicFile::commit() through ferror().
class TextOutput {
public:
  explicit TextOutput(std::FILE* file) : file_(file) { buffer_.reserve(kFlushSize + 256); }
  ~TextOutput() { flush(); }
  TextOutput(const TextOutput&) = delete;
  TextOutput& operator=(const TextOutput&) = delete;

  TextOutput& operator<<(std::string_view s);
  TextOutput& operator<<(char c);
  TextOutput& operator<<(std::int64_t v);
  TextOutput& operator<<(std::int32_t v) { return *this << std::int64_t(v); }
  TextOutput& operator<<(std::size_t v) { return *this << std::int64_t(v); }
  TextOutput& operator<<(double v);  // shortest exact representation
  void write(const void* bytes, std::size_t size);
  void flush();

private:
  static constexpr std::size_t kFlushSize = std::size_t(1) << 20;
  void maybeFlush() {
    if (buffer_.size() >= kFlushSize) flush();
  }
  std::FILE* file_;
  std::string buffer_;
};

}  // namespace vox::io
