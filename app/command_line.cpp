#include "app/command_line.h"

#include "geometry/io/atomic_file.h"
#include "geometry/progress.h"

#include <chrono>
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
  // A stage shows up only once it has run for a second, so quick steps stay
  // silent; then a terminal line is rewritten at most ten times a second and
  // a log gets a line every tenth of the work.
  using Clock = std::chrono::steady_clock;
  struct State {
    std::string stage;
    Clock::time_point started, lastPrint;
    int lastDecile = -1;
    bool shown = false;
  };
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  setProgressSink([tty, st = State()](std::string_view stage, double f) mutable {
    const auto now = Clock::now();
    if (stage != st.stage) st = State{std::string(stage), now, now, -1, false};
    const bool done = f >= 1.0;
    if (!st.shown && now - st.started < std::chrono::seconds(1)) return;
    const int percent = int(f * 100.0 + 0.5);
    if (tty) {
      if (!done && st.shown && now - st.lastPrint < std::chrono::milliseconds(100)) return;
      std::fprintf(stderr, "\r%.*s: %3d%%%s", int(stage.size()), stage.data(), percent, done ? "\n" : "");
      std::fflush(stderr);
    } else {
      const int decile = percent / 10;
      if (decile == st.lastDecile) return;
      st.lastDecile = decile;
      std::fprintf(stderr, "%.*s: %d%%\n", int(stage.size()), stage.data(), percent);
    }
    st.shown = true;
    st.lastPrint = now;
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
