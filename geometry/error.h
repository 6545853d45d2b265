#pragma once
// Errors that voxmorph reports to its user as one line and exit code 1.

#include <stdexcept>
#include <string>

namespace vox {

// Bad input: a file that cannot be read, is corrupt, or describes something
// the program refuses (overflowing dims, NaN coordinates, inverted tets...).
// The message names the file and the fault: "<path>: <what is wrong>".
class InputError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
  InputError(const std::string& path, const std::string& fault)
      : std::runtime_error(path + ": " + fault) {}
};

// A failure that is not the input's fault (disk full, GPU lost, ...).
class RuntimeFailure : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

}  // namespace vox
