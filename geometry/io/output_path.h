#pragma once
// Output paths checked before any work: a known extension for the kind of
// file, a parent directory that exists and is writable, and no directory
// under the target name. A run that would fail only when it writes (after
// minutes or hours of meshing or deformation) fails here instead.

#include <string>

namespace vox {

// Text: any extension (organ tables).
enum class OutputKind { Grid, TetMesh, Surface, Png, Json, Csv, Text, Prepared };

// Throws UsageError(option, ...) for an extension the kind's writers do not
// know, InputError(path, ...) for a missing or read-only directory. "-"
// (stdout) passes for Json. An empty path (option not given) passes.
void checkOutputPath(const std::string& path, OutputKind kind, const std::string& option);

}  // namespace vox
