#include "geometry/io/text_scanner.h"

#include "geometry/error.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace vox::io {

std::string readWholeFile(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(path, std::string("cannot open file (") + std::strerror(errno) + ")");
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat info {};
  if (::fstat(fd, &info) != 0) throw InputError(path, std::string("cannot read file (") + std::strerror(errno) + ")");
  if (!S_ISREG(info.st_mode)) throw InputError(path, "not a regular file");
  std::string bytes(std::size_t(info.st_size), '\0');
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw InputError(path, std::string("read error (") + std::strerror(errno) + ")");
    if (n == 0) break;
    done += std::size_t(n);
  }
  bytes.resize(done);
  return bytes;
}

std::string quoted(std::string_view token) {
  if (token.empty()) return "nothing";
  std::string s;
  for (char c : token.substr(0, 40)) s += (c >= 32 && c < 127) ? c : '?';
  return "'" + s + (token.size() > 40 ? "...'" : "'");
}

TextScanner::TextScanner(std::string_view text, const std::string& path, char comment, std::size_t firstLine)
    : text_(text), path_(path), comment_(comment), line_(firstLine) {}

bool TextScanner::skipSpace() {
  const std::size_t n = text_.size();
  while (pos_ < n) {
    const char c = text_[pos_];
    if (c == '\n') {
      ++line_;
      ++pos_;
    } else if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
      ++pos_;
    } else if (comment_ != '\0' && c == comment_) {
      while (pos_ < n && text_[pos_] != '\n') ++pos_;
    } else {
      return true;
    }
  }
  return false;
}

std::string_view TextScanner::word() {
  if (!skipSpace()) return {};
  const std::size_t start = pos_;
  const std::size_t n = text_.size();
  while (pos_ < n) {
    const char c = text_[pos_];
    if (c == ' ' || c == '\n' || c == '\t' || c == '\r' || c == '\f' || c == '\v') break;
    ++pos_;
  }
  return text_.substr(start, pos_ - start);
}

std::string_view TextScanner::peekWord() {
  // The whitespace before the token is consumed (and its lines counted); only
  // the token itself is left for the next word().
  const std::string_view w = word();
  if (!w.empty()) pos_ = std::size_t(w.data() - text_.data());
  return w;
}

std::int64_t TextScanner::integer(std::string_view what) {
  const std::string_view w = word();
  std::int64_t v = 0;
  const char* first = w.data();
  const char* last = w.data() + w.size();
  if (last - first > 1 && *first == '+' && first[1] != '-') ++first;
  const auto [end, ec] = std::from_chars(first, last, v);
  if (w.empty() || ec != std::errc() || end != last) {
    if (ec == std::errc::result_out_of_range) fail(std::string(what) + " " + quoted(w) + " is out of range");
    fail("expected " + std::string(what) + ", found " + quoted(w));
  }
  return v;
}

double TextScanner::real(std::string_view what) {
  const std::string_view w = word();
  double v = 0;
  const char* first = w.data();
  const char* last = w.data() + w.size();
  if (last - first > 1 && *first == '+' && first[1] != '-') ++first;
  const auto [end, ec] = std::from_chars(first, last, v);
  if (w.empty() || ec != std::errc() || end != last) {
    if (ec == std::errc::result_out_of_range) fail(std::string(what) + " " + quoted(w) + " is out of the double range");
    fail("expected " + std::string(what) + ", found " + quoted(w));
  }
  if (!std::isfinite(v)) fail(std::string(what) + " is not finite (" + quoted(w) + ")");
  return v;
}

std::size_t TextScanner::count(std::string_view what, std::size_t minBytesPerItem) {
  const std::int64_t n = integer(what);
  if (n < 0) fail(std::string(what) + " " + std::to_string(n) + " is negative");
  // The last item may lack its trailing separator.
  const std::size_t room = (remainingBytes() + 1) / minBytesPerItem;
  if (std::uint64_t(n) > room)
    fail(std::string(what) + " " + std::to_string(n) + " is more than the rest of the file can hold (" +
         std::to_string(remainingBytes()) + " bytes; truncated or corrupt file)");
  return std::size_t(n);
}

std::string_view TextScanner::restOfLine() {
  const std::size_t start = pos_;
  const std::size_t end = text_.find('\n', pos_);
  if (end == std::string_view::npos) {
    pos_ = text_.size();
    return text_.substr(start);
  }
  pos_ = end + 1;
  ++line_;
  std::string_view l = text_.substr(start, end - start);
  if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
  return l;
}

void TextScanner::advanceTo(std::size_t pos) {
  pos = std::min(pos, text_.size());
  if (pos <= pos_) return;
  line_ += std::size_t(std::count(text_.begin() + std::ptrdiff_t(pos_), text_.begin() + std::ptrdiff_t(pos), '\n'));
  pos_ = pos;
}

void TextScanner::fail(const std::string& fault) const {
  throw InputError(path_, "line " + std::to_string(line_) + ": " + fault);
}

TextOutput& TextOutput::operator<<(std::string_view s) {
  buffer_.append(s);
  maybeFlush();
  return *this;
}

TextOutput& TextOutput::operator<<(char c) {
  buffer_.push_back(c);
  maybeFlush();
  return *this;
}

TextOutput& TextOutput::operator<<(std::int64_t v) {
  char tmp[24];
  const auto r = std::to_chars(tmp, tmp + sizeof(tmp), v);
  buffer_.append(tmp, r.ptr);
  maybeFlush();
  return *this;
}

TextOutput& TextOutput::operator<<(double v) {
  char tmp[32];
  const auto r = std::to_chars(tmp, tmp + sizeof(tmp), v);
  buffer_.append(tmp, r.ptr);
  maybeFlush();
  return *this;
}

void TextOutput::write(const void* bytes, std::size_t size) {
  if (size >= kFlushSize) {
    flush();
    std::fwrite(bytes, 1, size, file_);
    return;
  }
  buffer_.append(static_cast<const char*>(bytes), size);
  maybeFlush();
}

void TextOutput::flush() {
  if (!buffer_.empty()) std::fwrite(buffer_.data(), 1, buffer_.size(), file_);
  buffer_.clear();
}

}  // namespace vox::io
