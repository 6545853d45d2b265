#pragma once
// The files a grid consists of, for digests of what a result was made from
// (provenance.h): the file itself, then the data file its header names where
// the samples live apart (.mhd + .raw, .nhdr + .raw.gz).

#include <string>
#include <vector>

namespace vox {

// Throws InputError for an unknown extension or a header that cannot be
// read.
std::vector<std::string> gridFiles(const std::string& path);

}  // namespace vox
