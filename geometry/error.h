#pragma once
// Errors that voxmorph reports to its user as one line: exit code 1, or 2 for
// a usage error.

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

// A bad command line: an option's value out of range or malformed, an output
// extension no writer knows. The message names the option and the fault:
// "<option>: <what is wrong>". Exit code 2, like the parser's own errors; an
// InputError for callers that do not tell the two apart.
class UsageError : public InputError {
public:
  UsageError(const std::string& option, const std::string& fault) : InputError(option, fault) {}
};

// A failure that is not the input's fault (disk full, GPU lost, ...).
class RuntimeFailure : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

}  // namespace vox
