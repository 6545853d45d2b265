#include "geometry/stage_timer.h"

#include <sys/resource.h>

namespace vox {

double processCpuSeconds() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

StageTimer::StageTimer(std::string name)
    : name_(std::move(name)), wall_(std::chrono::steady_clock::now()), cpu_(processCpuSeconds()) {}

StageTime StageTimer::stop() const {
  return {name_, std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_).count(), processCpuSeconds() - cpu_};
}

}  // namespace vox
