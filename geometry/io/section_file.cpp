#include "geometry/io/section_file.h"

#include "geometry/atomic_file.h"
#include "geometry/error.h"

#include <zlib.h>

#include <bit>
#include <cerrno>
#include <cstdio>
#include <limits>

namespace vox {

namespace {

// Deflate codes a 258-byte match in 2 bits at best (byte_stream.cpp).
constexpr std::uint64_t kMaxDeflateRatio = 1032;
constexpr std::size_t kHeaderBytes = 8 + 4 + 8 + 4;
constexpr std::size_t kTrailerBytes = 4;

std::uint32_t crc32Of(std::string_view bytes) {
  uLong crc = crc32(0L, Z_NULL, 0);
  std::size_t at = 0;
  while (at < bytes.size()) {
    const std::size_t n = std::min<std::size_t>(bytes.size() - at, std::size_t(1) << 30);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(bytes.data() + at), uInt(n));
    at += n;
  }
  return std::uint32_t(crc);
}

template <class T>
T load(const std::string& bytes, std::size_t at) {
  T v;
  std::memcpy(&v, bytes.data() + at, sizeof(T));
  return v;
}

}  // namespace

std::string SectionUnpacker::getString() {
  const std::uint64_t n = get<std::uint64_t>();
  if (n > remaining()) fail("a string", n);
  std::string s(bytes_.substr(at_, std::size_t(n)));
  at_ += std::size_t(n);
  return s;
}

std::size_t SectionUnpacker::getCount(std::size_t minBytes) {
  const std::uint64_t n = get<std::uint64_t>();
  if (minBytes > 0 && n > remaining() / minBytes) fail(std::to_string(n) + " items", n * minBytes);
  return std::size_t(n);
}

void SectionUnpacker::invalid(const std::string& fault) const { throw InputError(source_, "section '" + section_ + "': " + fault); }

void SectionUnpacker::fail(const std::string& what, std::uint64_t bytes) const {
  invalid("truncated (" + what + " needs " + std::to_string(bytes) + " bytes, " + std::to_string(remaining()) + " left)");
}

void SectionUnpacker::finish() const {
  if (remaining() != 0) invalid(std::to_string(remaining()) + " bytes left over");
}

void SectionFileWriter::add(std::string name, const std::string& packed) {
  if (name.size() > 255) throw RuntimeFailure("section name too long: " + name);
  uLongf bound = compressBound(uLong(packed.size()));
  std::string out(bound, '\0');
  if (compress2(reinterpret_cast<Bytef*>(out.data()), &bound, reinterpret_cast<const Bytef*>(packed.data()), uLong(packed.size()), 6) != Z_OK)
    throw RuntimeFailure("cannot compress section " + name);
  out.resize(bound);
  compressed_.emplace_back(std::move(name), std::move(out));
  packedSizes_.push_back(packed.size());
}

std::string SectionFileWriter::bytes() const {
  std::string out;
  out.append(kind_.magic.data(), 8);
  SectionPacker p;
  p.put(kind_.version);
  std::uint64_t total = kHeaderBytes + kTrailerBytes;
  for (const auto& [name, z] : compressed_) total += 2 + name.size() + 8 + 8 + z.size();
  p.put(total);
  p.put(std::uint32_t(compressed_.size()));
  out += p.bytes();
  for (std::size_t i = 0; i < compressed_.size(); ++i) {
    const auto& [name, z] = compressed_[i];
    SectionPacker h;
    h.put(std::uint16_t(name.size()));
    out += h.bytes();
    out += name;
    SectionPacker s;
    s.put(packedSizes_[i]);
    s.put(std::uint64_t(z.size()));
    out += s.bytes();
    out += z;
  }
  SectionPacker t;
  t.put(crc32Of(out));
  out += t.bytes();
  return out;
}

void SectionFileWriter::write(const std::string& path) const { writeFileAtomic(path, bytes()); }

SectionFile SectionFile::read(const std::string& path, const SectionFileKind& kind) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(path, std::string("cannot open (") + std::strerror(errno) + ")");
  std::string bytes;
  if (::fseeko(f, 0, SEEK_END) == 0) {
    const off_t size = ::ftello(f);
    if (size > 0 && ::fseeko(f, 0, SEEK_SET) == 0) {
      bytes.resize(std::size_t(size));  // the file's own size: what its bytes justify
      const std::size_t got = std::fread(bytes.data(), 1, bytes.size(), f);
      bytes.resize(got);
    }
  }
  const bool failed = std::ferror(f);
  std::fclose(f);
  if (failed) throw InputError(path, "read error");
  return parse(std::move(bytes), path, kind);
}

SectionFile SectionFile::parse(std::string bytes, const std::string& source, const SectionFileKind& kind) {
  if constexpr (std::endian::native != std::endian::little) throw RuntimeFailure(std::string(kind.what) + ": needs a little-endian machine");
  const std::string notOne = "not a " + std::string(kind.what) + " (" + std::string(kind.maker) + " writes them)";
  if (bytes.size() < 8 || std::string_view(bytes).substr(0, 8) != kind.magic) {
    if (bytes.size() < 8 && std::string_view(kind.magic).substr(0, bytes.size()) == bytes && !bytes.empty())
      throw InputError(source, "truncated (" + std::to_string(bytes.size()) + " bytes)");
    throw InputError(source, notOne);
  }
  if (bytes.size() < 12) throw InputError(source, "truncated (" + std::to_string(bytes.size()) + " bytes)");
  const auto version = load<std::uint32_t>(bytes, 8);
  if (version != kind.version)
    throw InputError(source, std::string(kind.what) + " format version " + std::to_string(version) + ", this voxmorph reads version " +
                                 std::to_string(kind.version) + " (" + std::string(kind.maker) + " makes it again)");
  if (bytes.size() < kHeaderBytes + kTrailerBytes) throw InputError(source, "truncated (" + std::to_string(bytes.size()) + " bytes)");
  const auto total = load<std::uint64_t>(bytes, 12);
  if (total > bytes.size())
    throw InputError(source, "truncated (" + std::to_string(bytes.size()) + " of " + std::to_string(total) + " bytes)");
  if (total < bytes.size())
    throw InputError(source, "corrupted (" + std::to_string(bytes.size() - total) + " bytes past its end of " + std::to_string(total) + ")");
  const std::size_t body = bytes.size() - kTrailerBytes;
  if (crc32Of(std::string_view(bytes).substr(0, body)) != load<std::uint32_t>(bytes, body))
    throw InputError(source, "corrupted (its checksum does not match its bytes)");

  SectionFile file;
  file.source_ = source;
  std::size_t at = kHeaderBytes;
  const auto count = load<std::uint32_t>(bytes, 20);
  const auto need = [&](std::size_t n) {
    if (n > body - at) throw InputError(source, "corrupted (a section runs past the end)");
  };
  if (count > (body - at) / (2 + 16)) throw InputError(source, "corrupted (" + std::to_string(count) + " sections)");
  for (std::uint32_t i = 0; i < count; ++i) {
    Entry e;
    need(2);
    const auto nameLength = load<std::uint16_t>(bytes, at);
    at += 2;
    need(nameLength);
    e.name = bytes.substr(at, nameLength);
    at += nameLength;
    need(16);
    e.packedSize = load<std::uint64_t>(bytes, at);
    const auto compressed = load<std::uint64_t>(bytes, at + 8);
    at += 16;
    need(std::size_t(std::min<std::uint64_t>(compressed, std::numeric_limits<std::size_t>::max())));
    if (compressed == 0 || e.packedSize > compressed * kMaxDeflateRatio)
      throw InputError(source, "corrupted (section '" + e.name + "' declares " + std::to_string(e.packedSize) + " bytes from " +
                                   std::to_string(compressed) + " compressed)");
    e.offset = at;
    e.compressedSize = std::size_t(compressed);
    at += e.compressedSize;
    file.entries_.push_back(std::move(e));
  }
  if (at != body) throw InputError(source, "corrupted (" + std::to_string(body - at) + " bytes after the last section)");
  file.bytes_ = std::move(bytes);
  return file;
}

std::vector<std::string> SectionFile::names() const {
  std::vector<std::string> out;
  for (const Entry& e : entries_) out.push_back(e.name);
  return out;
}

bool SectionFile::has(std::string_view name) const {
  for (const Entry& e : entries_)
    if (e.name == name) return true;
  return false;
}

std::string SectionFile::packed(std::string_view name) const {
  for (const Entry& e : entries_) {
    if (e.name != name) continue;
    std::string out(std::size_t(e.packedSize), '\0');
    uLongf size = uLongf(e.packedSize);
    const int rc = uncompress(reinterpret_cast<Bytef*>(out.data()), &size, reinterpret_cast<const Bytef*>(bytes_.data() + e.offset),
                              uLong(e.compressedSize));
    if (rc != Z_OK || size != e.packedSize)
      throw InputError(source_, "corrupted (section '" + e.name + "' does not inflate to its " + std::to_string(e.packedSize) + " bytes)");
    return out;
  }
  throw InputError(source_, "has no section '" + std::string(name) + "'");
}

}  // namespace vox
