#include "geometry/progress.h"

#include "geometry/cancellation.h"

#include <mutex>

namespace vox {

namespace {
std::mutex gMutex;
ProgressSink gSink;
thread_local std::atomic<bool>* tStop = nullptr;  // a ScopedCancellation's flag (null: none)
}  // namespace

void setProgressSink(ProgressSink sink) {
  std::lock_guard lock(gMutex);
  gSink = std::move(sink);
}

std::atomic<bool>& cancellationRequested() {
  static std::atomic<bool> requested{false};
  return requested;
}

void throwIfCancelled() {
  if (cancellationRequested().load(std::memory_order_relaxed) || (tStop && tStop->load(std::memory_order_relaxed)))
    throw OperationCancelled();
}

std::atomic<bool>& cancellationFlag() { return tStop ? *tStop : cancellationRequested(); }

ScopedCancellation::ScopedCancellation(std::atomic<bool>& flag) : outer_(tStop) { tStop = &flag; }

ScopedCancellation::~ScopedCancellation() { tStop = outer_; }

void reportProgress(std::string_view stage, double fraction) {
  throwIfCancelled();
  std::lock_guard lock(gMutex);
  if (gSink) gSink(stage, fraction);
}

ProgressCounter::ProgressCounter(std::string_view stage, double total) : stage_(stage), total_(total > 0 ? total : 1.0) {
  reportProgress(stage_, 0.0);
}

void ProgressCounter::advance(double units) {
  done_ += units;
  const int percent = int(100.0 * done_ / total_);
  if (percent != lastPercent_ && percent < 100) {
    lastPercent_ = percent;
    reportProgress(stage_, done_ / total_);
  }
}

void ProgressCounter::finish() { reportProgress(stage_, 1.0); }

}  // namespace vox
