#include "python/interruptible.h"

#include "geometry/cancellation.h"

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

namespace vox::python {

void runInterruptible(const std::function<void()>& work) {
  std::exception_ptr failure;
  std::mutex mutex;
  std::condition_variable done;
  bool finished = false;
  bool interrupted = false;
  {
    pybind11::gil_scoped_release release;
    std::thread worker([&] {
      try {
        work();
      } catch (...) {
        failure = std::current_exception();
      }
      std::lock_guard lock(mutex);
      finished = true;
      done.notify_all();
    });
    std::unique_lock lock(mutex);
    while (!done.wait_for(lock, std::chrono::milliseconds(50), [&] { return finished; })) {
      if (interrupted) continue;
      lock.unlock();
      {
        pybind11::gil_scoped_acquire acquire;
        // The handler's exception (KeyboardInterrupt) stays set while the
        // work unwinds.
        if (PyErr_CheckSignals() != 0) {
          interrupted = true;
          cancellationRequested() = true;
        }
      }
      lock.lock();
    }
    lock.unlock();
    worker.join();
    if (interrupted) cancellationRequested() = false;
  }
  if (interrupted) throw pybind11::error_already_set();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace vox::python
