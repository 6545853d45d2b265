#pragma once
// Long calls from Python: the work runs on a worker thread with the GIL
// released while the calling thread waits, checking for signals every 50 ms.
// Ctrl-C (KeyboardInterrupt, or any signal handler that raises) requests
// cancellation (geometry/cancellation.h): the work stops at its next progress
// report and unwinds as on any error, so atomic writers leave no partial
// file, and the Python exception is raised once the worker has stopped.

#include <pybind11/pybind11.h>

#include <exception>
#include <functional>
#include <optional>
#include <utility>

namespace vox::python {

// Runs `work` as described above; rethrows its exception, or raises the
// signal handler's exception when the call was interrupted.
void runInterruptible(const std::function<void()>& work);

template <class F>
auto interruptible(F&& work) -> decltype(work()) {
  std::optional<decltype(work())> result;
  runInterruptible([&] { result.emplace(work()); });
  return std::move(*result);
}

}  // namespace vox::python
