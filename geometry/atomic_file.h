#pragma once
// Atomic output: write to a temporary file beside the target, then rename.
// A crash or an exception never leaves a half-written file under the target
// name, and an existing target is replaced only when the new file is complete.

#include <cstdio>
#include <string>

namespace vox {

class AtomicFile {
public:
  // `target` is the final path. The temporary name keeps the target's
  // extension (".tmp-<pid>-<n>.<target name>") so format-sniffing libraries
  // see the right suffix.
  explicit AtomicFile(std::string target);
  ~AtomicFile();  // removes the temporary unless commit() succeeded
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::string& target() const { return target_; }
  const std::string& tempPath() const { return temp_; }

  // Opens the temporary with stdio ("wb"); throws RuntimeFailure on error.
  std::FILE* openStdio();
  // Checks stdio errors, flushes, closes, fsyncs and renames onto the target.
  // Throws RuntimeFailure naming the target on any failure.
  void commit();

private:
  std::string target_;
  std::string temp_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
};

// Writes `bytes` to `path` atomically.
void writeFileAtomic(const std::string& path, const std::string& bytes);

}  // namespace vox
