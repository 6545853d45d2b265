#pragma once
// Stage timing for reports: wall and process CPU seconds of a named stage.

#include <chrono>
#include <string>

namespace vox {

// Wall and process CPU time of one stage (CPU time counts every thread, so
// on a loaded machine it is the steadier figure).
struct StageTime {
  std::string name;
  double seconds = 0.0;
  double cpuSeconds = 0.0;
};

// Times a stage from construction to stop().
class StageTimer {
public:
  explicit StageTimer(std::string name);
  StageTime stop() const;

private:
  std::string name_;
  std::chrono::steady_clock::time_point wall_;
  double cpu_ = 0.0;
};
// Process CPU seconds (user + system, every thread) so far.
double processCpuSeconds();

}  // namespace vox
