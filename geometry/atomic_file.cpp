#include "geometry/atomic_file.h"

#include "geometry/error.h"

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <unistd.h>

namespace vox {

namespace {
std::atomic<unsigned> gTempCounter{0};
std::string errnoText() { return std::strerror(errno); }
}  // namespace

AtomicFile::AtomicFile(std::string target) : target_(std::move(target)) {
  const std::filesystem::path p(target_);
  const std::string name = p.filename().string();
  const std::string tmpName = ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(gTempCounter++) + "." + name;
  temp_ = (p.parent_path() / tmpName).string();
}

AtomicFile::~AtomicFile() {
  if (file_) std::fclose(file_);
  if (!committed_) {
    std::error_code ec;
    std::filesystem::remove(temp_, ec);
  }
}

std::FILE* AtomicFile::openStdio() {
  if (file_) return file_;
  file_ = std::fopen(temp_.c_str(), "wb");
  if (!file_) throw RuntimeFailure(target_ + ": cannot create output file (" + errnoText() + ")");
  return file_;
}

void AtomicFile::commit() {
  if (file_) {
    const bool bad = std::ferror(file_) != 0 || std::fflush(file_) != 0;
    const int fd = ::fileno(file_);
    if (!bad) ::fsync(fd);
    const bool closeFailed = std::fclose(file_) != 0;
    file_ = nullptr;
    if (bad || closeFailed) throw RuntimeFailure(target_ + ": write failed (" + errnoText() + ")");
  }
  std::error_code ec;
  if (!std::filesystem::exists(temp_, ec)) throw RuntimeFailure(target_ + ": nothing was written");
  std::filesystem::rename(temp_, target_, ec);
  if (ec) throw RuntimeFailure(target_ + ": cannot rename temporary output into place (" + ec.message() + ")");
  committed_ = true;
}

void writeFileAtomic(const std::string& path, const std::string& bytes) {
  AtomicFile out(path);
  std::FILE* f = out.openStdio();
  if (!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size())
    throw RuntimeFailure(path + ": write failed (" + errnoText() + ")");
  out.commit();
}

}  // namespace vox
