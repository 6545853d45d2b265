#pragma once
// Cancelling long work from another thread (the Python module's Ctrl-C).
// Once cancellation is requested, the next progress report (progress.h)
// throws OperationCancelled, so the work unwinds as on any error and atomic
// writers leave no file. CGAL's mesher, which reports no progress while it
// refines, polls the flag itself (restricted_delaunay_cgal.cpp).

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <vector>

namespace vox {

class OperationCancelled : public std::runtime_error {
public:
  OperationCancelled() : std::runtime_error("cancelled") {}
};

// Process-wide; whoever sets it clears it once the cancelled work has
// unwound (work started meanwhile stops too).
std::atomic<bool>& cancellationRequested();

// Throws OperationCancelled while cancellation is requested, or while the
// flag of a ScopedCancellation on the calling thread is set.
void throwIfCancelled();

// std::sort that polls for cancellation every 65536 comparisons: a sort of a
// whole mesh's faces or edges runs for a second and more. The same
// comparisons in the same order as std::sort, so the same result; cancelled,
// the range is left in some order (the work it belonged to is discarded).
template <typename It, typename Less = std::less<>>
void sortCancellable(It first, It last, Less less = {}) {
  std::uint32_t compared = 0;
  std::sort(first, last, [&](const auto& a, const auto& b) {
    if ((++compared & 0xFFFFu) == 0) throwIfCancelled();
    return less(a, b);
  });
}

// Large arrays written in chunks that poll for cancellation between them:
// filling a gigabyte (its pages faulted in) takes a second and more.
inline constexpr std::size_t kCancellableChunk = std::size_t(1) << 22;  // elements

// n copies of value.
template <typename T>
std::vector<T> filledCancellable(std::size_t n, const T& value) {
  std::vector<T> v;
  v.reserve(n);
  while (v.size() < n) {
    throwIfCancelled();
    v.insert(v.end(), std::min(kCancellableChunk, n - v.size()), value);
  }
  return v;
}

// Appends [first, last) to v.
template <typename T, typename It>
void appendCancellable(std::vector<T>& v, It first, It last) {
  v.reserve(v.size() + std::size_t(last - first));
  while (first != last) {
    throwIfCancelled();
    const It end = first + std::min<std::ptrdiff_t>(std::ptrdiff_t(kCancellableChunk), last - first);
    v.insert(v.end(), first, end);
    first = end;
  }
}

// The flag that stops the calling thread's work: a ScopedCancellation's
// while one lives on this thread, else the process-wide one. CGAL's mesher,
// which polls a single flag, polls this one.
std::atomic<bool>& cancellationFlag();

// A stop request for the work of one thread (a stage built on a thread of
// its own beside another, stopped when the other fails): while it lives,
// throwIfCancelled on the constructing thread throws once `flag` is set, as
// well as on the process-wide request, and cancellationFlag() is `flag`.
// Whoever owns `flag` sets it on the process-wide request too (the mesher
// polls `flag` alone). The parallel loop carries it to its workers. Scopes
// nest; the destructor restores the outer one.
class ScopedCancellation {
public:
  explicit ScopedCancellation(std::atomic<bool>& flag);
  ~ScopedCancellation();
  ScopedCancellation(const ScopedCancellation&) = delete;
  ScopedCancellation& operator=(const ScopedCancellation&) = delete;

private:
  std::atomic<bool>* outer_;
};

}  // namespace vox
