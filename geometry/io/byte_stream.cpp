#include "geometry/io/byte_stream.h"

#include "geometry/error.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <limits>
#include <new>
#include <vector>

namespace vox {

namespace {

constexpr std::size_t kBufferBytes = std::size_t(1) << 18;
// zlib counts in unsigned int: feed it at most this much at a time.
constexpr std::size_t kZlibChunk = std::size_t(1) << 30;
// Deflate codes a 258-byte match in 2 bits at best; each stream adds at most
// one such match's worth of slack.
constexpr std::int64_t kMaxDeflateRatio = 1032;

std::string errnoText() { return std::strerror(errno); }

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using FileHandle = std::unique_ptr<std::FILE, FileCloser>;

class PlainReader final : public ByteReader {
public:
  PlainReader(std::FILE* file, std::uint64_t start, std::string source) : file_(file), start_(start), source_(std::move(source)) {
    if (::fseeko(file, 0, SEEK_END) != 0) throw InputError(source_, "cannot seek (" + errnoText() + ")");
    const std::int64_t total = ::ftello(file);
    size_ = total > std::int64_t(start_) ? total - std::int64_t(start_) : 0;
    seek(0);
  }
  std::size_t read(void* dst, std::size_t n) override {
    const std::size_t got = std::fread(dst, 1, n, file_.get());
    if (got < n && std::ferror(file_.get())) throw InputError(source_, "read error (" + errnoText() + ")");
    return got;
  }
  void seek(std::uint64_t offset) override {
    if (::fseeko(file_.get(), off_t(start_ + offset), SEEK_SET) != 0) throw InputError(source_, "cannot seek (" + errnoText() + ")");
  }
  std::int64_t size() const override { return size_; }
  std::int64_t maxSize() const override { return size_; }
  void checkEnd() override {}

private:
  FileHandle file_;
  std::uint64_t start_;
  std::string source_;
  std::int64_t size_ = 0;
};

class InflateReader final : public ByteReader {
public:
  InflateReader(std::FILE* file, std::uint64_t start, std::string source)
      : file_(file), start_(start), source_(std::move(source)), input_(kBufferBytes) {
    if (::fseeko(file, 0, SEEK_END) != 0) throw InputError(source_, "cannot seek (" + errnoText() + ")");
    const std::int64_t total = ::ftello(file);
    const std::int64_t compressed = total > std::int64_t(start_) ? total - std::int64_t(start_) : 0;
    maxSize_ = compressed > std::numeric_limits<std::int64_t>::max() / kMaxDeflateRatio - 1
                   ? std::numeric_limits<std::int64_t>::max()
                   : (compressed + 1) * kMaxDeflateRatio;
    restart();
  }
  ~InflateReader() override {
    if (initialized_) inflateEnd(&z_);
  }

  std::size_t read(void* dst, std::size_t n) override {
    std::size_t total = 0;
    auto* out = static_cast<unsigned char*>(dst);
    while (total < n && !streamEnd_) {
      const std::size_t chunk = std::min(n - total, kZlibChunk);
      z_.next_out = out + total;
      z_.avail_out = unsigned(chunk);
      const bool progressed = inflateSome();
      total += chunk - z_.avail_out;
      if (!progressed) break;
    }
    position_ += total;
    return total;
  }

  void seek(std::uint64_t offset) override {
    if (offset < position_) restart();
    std::vector<unsigned char> scratch(std::size_t(std::min<std::uint64_t>(kBufferBytes, offset - position_)));
    while (position_ < offset) {
      const std::size_t want = std::size_t(std::min<std::uint64_t>(scratch.size(), offset - position_));
      if (read(scratch.data(), want) == 0) return;  // the caller's next read reports the truncation
    }
  }

  std::int64_t size() const override { return -1; }
  std::int64_t maxSize() const override { return maxSize_; }

  void checkEnd() override {
    std::vector<unsigned char> scratch(kBufferBytes);
    while (!streamEnd_) {
      if (read(scratch.data(), scratch.size()) == 0 && !streamEnd_)
        throw InputError(source_, "compressed data is truncated (the stream ends before its end marker and checksum)");
    }
  }

private:
  void restart() {
    if (initialized_) inflateEnd(&z_);
    initialized_ = false;
    z_ = z_stream{};
    // 15 + 32: zlib or gzip header, detected automatically.
    if (inflateInit2(&z_, 15 + 32) != Z_OK) throw std::bad_alloc();
    initialized_ = true;
    if (::fseeko(file_.get(), off_t(start_), SEEK_SET) != 0) throw InputError(source_, "cannot seek (" + errnoText() + ")");
    inputEnd_ = false;
    streamEnd_ = false;
    position_ = 0;
  }

  // Keeps what zlib has not consumed and appends more of the file.
  void refill() {
    const std::size_t kept = z_.avail_in;
    if (kept > 0 && z_.next_in != input_.data()) std::memmove(input_.data(), z_.next_in, kept);
    const std::size_t got = std::fread(input_.data() + kept, 1, input_.size() - kept, file_.get());
    if (got < input_.size() - kept) {
      if (std::ferror(file_.get())) throw InputError(source_, "read error (" + errnoText() + ")");
      inputEnd_ = true;
    }
    z_.next_in = input_.data();
    z_.avail_in = unsigned(kept + got);
  }

  // One inflate step into z_.next_out; returns false when nothing more can be
  // produced (end of stream or end of input).
  bool inflateSome() {
    if (z_.avail_in == 0 && !inputEnd_) refill();
    const unsigned outBefore = z_.avail_out;
    const int ret = inflate(&z_, Z_NO_FLUSH);
    if (ret == Z_STREAM_END) {
      // Concatenated gzip members decode as one stream (as gzip -d does).
      if (z_.avail_in < 2 && !inputEnd_) refill();
      if (z_.avail_in >= 2 && z_.next_in[0] == 0x1f && z_.next_in[1] == 0x8b) {
        inflateReset(&z_);
        return true;
      }
      streamEnd_ = true;
      return false;
    }
    if (ret == Z_DATA_ERROR || ret == Z_NEED_DICT || ret == Z_STREAM_ERROR)
      throw InputError(source_, std::string("corrupt compressed data (") + (z_.msg ? z_.msg : "invalid stream") + ")");
    if (ret == Z_MEM_ERROR) throw std::bad_alloc();
    if (z_.avail_out != outBefore) return true;
    // Nothing came out: only more input can change that.
    return !(z_.avail_in == 0 && inputEnd_);
  }

  FileHandle file_;
  std::uint64_t start_;
  std::string source_;
  std::vector<unsigned char> input_;
  z_stream z_{};
  bool initialized_ = false;
  bool inputEnd_ = false;
  bool streamEnd_ = false;
  std::uint64_t position_ = 0;
  std::int64_t maxSize_ = 0;
};

class StdioWriter final : public ByteWriter {
public:
  StdioWriter(std::FILE* file, std::string target) : file_(file), target_(std::move(target)) {}
  void write(const void* src, std::size_t n) override {
    if (n > 0 && std::fwrite(src, 1, n, file_) != n) throw RuntimeFailure(target_ + ": write failed (" + errnoText() + ")");
  }
  void finish() override {
    if (std::fflush(file_) != 0) throw RuntimeFailure(target_ + ": write failed (" + errnoText() + ")");
  }

private:
  std::FILE* file_;
  std::string target_;
};

class StringWriter final : public ByteWriter {
public:
  explicit StringWriter(std::string& out) : out_(out) {}
  void write(const void* src, std::size_t n) override { out_.append(static_cast<const char*>(src), n); }
  void finish() override {}

private:
  std::string& out_;
};

class DeflateWriter final : public ByteWriter {
public:
  DeflateWriter(ByteWriter& out, DeflateWrapper wrapper, std::string target)
      : out_(out), target_(std::move(target)), buffer_(kBufferBytes) {
    // Level 6 is zlib's default: label grids compress 20-50x at about the
    // speed of level 1, whose output is noticeably larger on them.
    const int windowBits = wrapper == DeflateWrapper::Gzip ? 15 + 16 : 15;
    if (deflateInit2(&z_, 6, Z_DEFLATED, windowBits, 8, Z_DEFAULT_STRATEGY) != Z_OK) throw std::bad_alloc();
  }
  ~DeflateWriter() override { deflateEnd(&z_); }

  void write(const void* src, std::size_t n) override {
    const auto* in = static_cast<const unsigned char*>(src);
    while (n > 0) {
      const std::size_t chunk = std::min(n, kZlibChunk);
      z_.next_in = const_cast<unsigned char*>(in);
      z_.avail_in = unsigned(chunk);
      while (z_.avail_in > 0) deflateStep(Z_NO_FLUSH);
      in += chunk;
      n -= chunk;
    }
  }
  void finish() override {
    z_.next_in = nullptr;
    z_.avail_in = 0;
    while (deflateStep(Z_FINISH) != Z_STREAM_END) {
    }
    out_.finish();
  }

private:
  int deflateStep(int flush) {
    z_.next_out = buffer_.data();
    z_.avail_out = unsigned(buffer_.size());
    const int ret = deflate(&z_, flush);
    if (ret == Z_STREAM_ERROR) throw RuntimeFailure(target_ + ": compression failed");
    out_.write(buffer_.data(), buffer_.size() - z_.avail_out);
    return ret;
  }

  ByteWriter& out_;
  std::string target_;
  std::vector<unsigned char> buffer_;
  z_stream z_{};
};

}  // namespace

bool isGzipFile(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  unsigned char magic[2] = {0, 0};
  const bool gz = std::fread(magic, 1, 2, f) == 2 && magic[0] == 0x1f && magic[1] == 0x8b;
  std::fclose(f);
  return gz;
}

std::FILE* openForReading(const std::string& path, const std::string& source) {
  const std::string what = path == source ? std::string("the file") : "its data file " + path;
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError(source, "cannot read " + what + " (it is a directory)");
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(source, "cannot open " + what + " (" + errnoText() + ")");
  return f;
}

std::unique_ptr<ByteReader> plainReader(std::FILE* file, std::uint64_t start, std::string source) {
  return std::make_unique<PlainReader>(file, start, std::move(source));
}

std::unique_ptr<ByteReader> inflateReader(std::FILE* file, std::uint64_t start, std::string source) {
  return std::make_unique<InflateReader>(file, start, std::move(source));
}

void readExactly(ByteReader& in, void* dst, std::size_t n, const std::string& source, const std::string& what) {
  const std::size_t got = in.read(dst, n);
  if (got != n)
    throw InputError(source, what + " is truncated (" + std::to_string(got) + " of " + std::to_string(n) + " bytes present)");
}

std::unique_ptr<ByteWriter> stdioWriter(std::FILE* file, std::string target) {
  return std::make_unique<StdioWriter>(file, std::move(target));
}

std::unique_ptr<ByteWriter> stringWriter(std::string& out) { return std::make_unique<StringWriter>(out); }

std::unique_ptr<ByteWriter> deflateWriter(ByteWriter& out, DeflateWrapper wrapper, std::string target) {
  return std::make_unique<DeflateWriter>(out, wrapper, std::move(target));
}

}  // namespace vox
