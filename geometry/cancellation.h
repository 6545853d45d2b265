#pragma once
// Cancelling long work from another thread (the Python module's Ctrl-C).
// Once cancellation is requested, the next progress report (progress.h)
// throws OperationCancelled, so the work unwinds as on any error and atomic
// writers leave no file. CGAL's mesher, which reports no progress while it
// refines, polls the flag itself (restricted_delaunay_cgal.cpp).

#include <atomic>
#include <stdexcept>

namespace vox {

class OperationCancelled : public std::runtime_error {
public:
  OperationCancelled() : std::runtime_error("cancelled") {}
};

// Process-wide; whoever sets it clears it once the cancelled work has
// unwound (work started meanwhile stops too).
std::atomic<bool>& cancellationRequested();

// Throws OperationCancelled while cancellation is requested.
void throwIfCancelled();

}  // namespace vox
