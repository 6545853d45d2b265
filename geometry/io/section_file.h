#pragma once
// A versioned binary container of named, zlib-compressed sections, with the
// little-endian packing of what goes into a section. voxmorph's saved rest
// state (deform/prepared_state.h) is one; the layout:
//
//   8 bytes   magic (the kind of file)
//   u32       format version
//   u64       total bytes of the file, this trailer included
//   u32       section count
//   per section: u16 name length, name, u64 packed bytes, u64 compressed
//             bytes, the compressed bytes (zlib)
//   u32       CRC-32 of every byte before it
//
// The reader checks, in this order, the magic, the version, the length
// (a shorter file is "truncated"), the CRC ("corrupted"), then every count
// against the bytes that remain before it allocates anything: a section's
// packed size against deflate's largest ratio to its compressed bytes, a
// vector's element count against the packed bytes left (docs/ARCHITECTURE.md,
// "Readers allocate only what the bytes they have can justify"). Every fault
// is an InputError naming the file and what is wrong, one line.

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace vox {

// Packs plain values and vectors of them (native little-endian layout: the
// readers run where the writers do; the reader refuses a big-endian host).
class SectionPacker {
public:
  template <class T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const char*>(&value);
    bytes_.append(p, sizeof(T));
  }
  void putString(std::string_view s) {
    put(std::uint64_t(s.size()));
    bytes_.append(s.data(), s.size());
  }
  template <class T>
  void putVector(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    put(std::uint64_t(v.size()));
    if (!v.empty()) bytes_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
  const std::string& bytes() const { return bytes_; }
  std::string take() { return std::move(bytes_); }

private:
  std::string bytes_;
};

// Reads what SectionPacker packed; every read is checked against the bytes
// left: InputError(source, "<section>: truncated ...") otherwise.
class SectionUnpacker {
public:
  SectionUnpacker(std::string_view bytes, std::string source, std::string section)
      : bytes_(bytes), source_(std::move(source)), section_(std::move(section)) {}

  template <class T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T), "a value");
    T value;
    std::memcpy(&value, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return value;
  }
  std::string getString();
  template <class T>
  std::vector<T> getVector() {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::uint64_t n = get<std::uint64_t>();
    if (n > (bytes_.size() - at_) / sizeof(T)) fail(std::to_string(n) + " elements of " + std::to_string(sizeof(T)) + " bytes", n * sizeof(T));
    std::vector<T> v(static_cast<std::size_t>(n));
    if (n > 0) std::memcpy(v.data(), bytes_.data() + at_, std::size_t(n) * sizeof(T));
    at_ += std::size_t(n) * sizeof(T);
    return v;
  }
  // A count of items of at least `minBytes` packed bytes each, checked
  // against the bytes left.
  std::size_t getCount(std::size_t minBytes);
  std::size_t remaining() const { return bytes_.size() - at_; }
  // Throws InputError(source, "<section>: <fault>").
  [[noreturn]] void invalid(const std::string& fault) const;
  // Throws unless every byte was read.
  void finish() const;

private:
  void need(std::size_t n, const char* what) const {
    if (n > bytes_.size() - at_) fail(what, n);
  }
  [[noreturn]] void fail(const std::string& what, std::uint64_t bytes) const;

  std::string_view bytes_;
  std::size_t at_ = 0;
  std::string source_, section_;
};

struct SectionFileKind {
  std::string_view magic;  // 8 bytes
  std::uint32_t version;
  std::string_view what;   // "voxmorph prepared state" (in messages)
  std::string_view maker;  // "voxmorph prepare" (in messages: "... writes them")
};

class SectionFileWriter {
public:
  explicit SectionFileWriter(const SectionFileKind& kind) : kind_(kind) {}
  // Compresses `packed` (zlib, level 6) under `name` (at most 255 bytes).
  void add(std::string name, const std::string& packed);
  // The whole file's bytes.
  std::string bytes() const;
  // Writes them atomically (atomic_file.h).
  void write(const std::string& path) const;

private:
  SectionFileKind kind_;
  std::vector<std::pair<std::string, std::string>> compressed_;  // name, zlib bytes
  std::vector<std::uint64_t> packedSizes_;
};

class SectionFile {
public:
  // Reads and checks `path` (see above); the sections stay compressed until
  // unpacked.
  static SectionFile read(const std::string& path, const SectionFileKind& kind);
  // The same from bytes in memory (`source` names them in errors).
  static SectionFile parse(std::string bytes, const std::string& source, const SectionFileKind& kind);

  const std::string& source() const { return source_; }
  std::vector<std::string> names() const;
  bool has(std::string_view name) const;
  // The section's packed bytes, inflated (InputError naming the file when
  // it is missing or does not inflate to its declared size).
  std::string packed(std::string_view name) const;
  SectionUnpacker unpacker(std::string_view name, std::string& storage) const {
    storage = packed(name);
    return SectionUnpacker(storage, source_, std::string(name));
  }

private:
  struct Entry {
    std::string name;
    std::uint64_t packedSize = 0;
    std::size_t offset = 0, compressedSize = 0;
  };
  std::string bytes_, source_;
  std::vector<Entry> entries_;
};

}  // namespace vox
