#pragma once
// Progress of long operations, reported to a process-wide sink (the CLI
// prints it on stderr; the library is silent unless a sink is installed).

#include <functional>
#include <string_view>

namespace vox {

// fraction in [0, 1]; 1 marks the end of the stage.
using ProgressSink = std::function<void(std::string_view stage, double fraction)>;

void setProgressSink(ProgressSink sink);
void reportProgress(std::string_view stage, double fraction);

// Reports `stage` as work units complete, at most about 100 times.
class ProgressCounter {
public:
  ProgressCounter(std::string_view stage, double total);
  void advance(double units = 1.0);
  void finish();

private:
  std::string_view stage_;
  double total_;
  double done_ = 0.0;
  int lastPercent_ = -1;
};

}  // namespace vox
