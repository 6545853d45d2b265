#include "app/command_line.h"

#include "geometry/io/atomic_file.h"
#include "geometry/progress.h"

#include <cstdio>
#include <iostream>
#include <string>
#include <unistd.h>

namespace vox::app {

void installStderrProgress(bool quiet) {
  if (quiet) {
    setProgressSink({});
    return;
  }
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  setProgressSink([tty, lastStage = std::string(), lastDecile = -1](std::string_view stage, double f) mutable {
    const int percent = int(f * 100.0 + 0.5);
    if (tty) {
      std::fprintf(stderr, "\r%.*s: %3d%%%s", int(stage.size()), stage.data(), percent, f >= 1.0 ? "\n" : "");
      std::fflush(stderr);
      return;
    }
    const int decile = percent / 10;
    if (stage != lastStage || decile != lastDecile) {
      std::fprintf(stderr, "%.*s: %d%%\n", int(stage.size()), stage.data(), percent);
      lastStage = stage;
      lastDecile = decile;
    }
  });
}

void writeJson(const std::string& path, const nlohmann::json& json) {
  const std::string text = json.dump(2) + "\n";
  if (path == "-") {
    std::cout << text;
    return;
  }
  writeFileAtomic(path, text);
}

std::string withThousands(std::uint64_t n) {
  std::string s = std::to_string(n);
  for (int i = int(s.size()) - 3; i > 0; i -= 3) s.insert(std::size_t(i), ",");
  return s;
}

}  // namespace vox::app
