#pragma once
// Byte streams under the grid formats: plain files with random access, and
// zlib / gzip payloads decoded or encoded on the fly, so that a grid is never
// held twice in memory and slices can be streamed. Internal to geometry/io.

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

namespace vox {

// Input. Failures throw InputError naming `source` (the file the user gave,
// plus the data file when it is a separate one).
class ByteReader {
public:
  virtual ~ByteReader() = default;
  // Reads up to n bytes; fewer only where the data ends.
  virtual std::size_t read(void* dst, std::size_t n) = 0;
  // Moves to byte `offset` of the (decoded) stream. Compressed streams skip
  // forward by decoding and restart from their beginning to go back.
  virtual void seek(std::uint64_t offset) = 0;
  // Bytes in the stream when known without decoding it (plain files), else -1.
  virtual std::int64_t size() const = 0;
  // The most bytes the stream can hold: size() for plain files; for
  // compressed streams the bound deflate's largest ratio (1032:1) puts on the
  // bytes left in the file, so that a header declaring more is rejected
  // before anything is allocated from it.
  virtual std::int64_t maxSize() const = 0;
  // Compressed streams: decodes what remains and checks that the stream ends
  // with a valid checksum (truncated or corrupt archives are caught here even
  // when every voxel was already read).
  virtual void checkEnd() = 0;
};

// True when the file starts with the gzip magic bytes.
bool isGzipFile(const std::string& path);
// Throws InputError(source, "cannot open ...") when the file cannot be opened.
std::FILE* openForReading(const std::string& path, const std::string& source);

// The bytes of `file` from `start` on. Takes ownership of the file.
std::unique_ptr<ByteReader> plainReader(std::FILE* file, std::uint64_t start, std::string source);
// A zlib or gzip stream (detected from its header; concatenated gzip members
// are read as one) starting at byte `start` of `file`. Takes ownership.
std::unique_ptr<ByteReader> inflateReader(std::FILE* file, std::uint64_t start, std::string source);

// Reads exactly n bytes or throws InputError(source, "<what> is truncated ...").
void readExactly(ByteReader& in, void* dst, std::size_t n, const std::string& source, const std::string& what);

// Output. Failures throw RuntimeFailure naming the target.
class ByteWriter {
public:
  virtual ~ByteWriter() = default;
  virtual void write(const void* src, std::size_t n) = 0;
  // Flushes what the writer buffers (compressed streams write their trailer).
  virtual void finish() = 0;
};

// Appends to a stdio file (owned by the caller, e.g. AtomicFile).
std::unique_ptr<ByteWriter> stdioWriter(std::FILE* file, std::string target);
// Appends to a string.
std::unique_ptr<ByteWriter> stringWriter(std::string& out);

enum class DeflateWrapper { Zlib, Gzip };
// Compresses into `out` (which must outlive it); finish() also finishes `out`.
std::unique_ptr<ByteWriter> deflateWriter(ByteWriter& out, DeflateWrapper wrapper, std::string target);

}  // namespace vox
