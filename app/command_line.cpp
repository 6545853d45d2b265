#include "app/command_line.h"

#include "geometry/ascii_text.h"
#include "geometry/error.h"
#include "geometry/atomic_file.h"
#include "geometry/io/grid_io.h"
#include "geometry/io/input_provenance.h"
#include "geometry/progress.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <malloc.h>
#include <string>
#include <string_view>
#include <sys/resource.h>
#include <unistd.h>

namespace vox::app {

void retainFreedMemory() {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
}

void useHugePages(int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') return;  // no subcommand: help or version
  if (std::getenv("VOXMORPH_SMALL_PAGES") != nullptr) return;
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  const std::string_view kTunable = "glibc.malloc.hugetlb";
  if (tunables != nullptr && std::string_view(tunables).find(kTunable) != std::string_view::npos) return;
  std::ifstream mode("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  if (!std::getline(mode, line) || line.find("[madvise]") == std::string::npos) return;
  const std::string before = tunables != nullptr ? tunables : "";
  const std::string value = (before.empty() ? before : before + ":") + std::string(kTunable) + "=1";
  if (::setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  ::execv("/proc/self/exe", argv);
  // Not started again (no /proc): on as it is, without the setting.
  if (tunables != nullptr) ::setenv("GLIBC_TUNABLES", before.c_str(), 1);
  else ::unsetenv("GLIBC_TUNABLES");
}

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

namespace {
std::string& commandLineText() {
  static std::string text;
  return text;
}
}  // namespace

CLI::App* addGridSubcommand(CLI::App& app, const std::string& name, const std::string& description, std::string& grid) {
  CLI::App* cmd = app.add_subcommand(name, description);
  cmd->add_option("grid", grid, "Label grid (.nii .nii.gz .mha .mhd .nrrd .nhdr .inr)")->required();
  return cmd;
}

void recordCommandLine(int argc, const char* const* argv) { commandLineText() = shellCommandLine(argc, argv); }
const std::string& recordedCommandLine() { return commandLineText(); }

Provenance commandProvenance(const std::vector<std::pair<std::string, std::string>>& files) {
  return makeProvenance(recordedCommandLine(), files);
}

void writeJson(const std::string& path, const nlohmann::json& json) {
  const std::string text = json.dump(2) + "\n";
  if (path == "-") {
    std::cout << text;
    return;
  }
  writeFileAtomic(path, text);
}

CLI::Validator numberIn(double lo, double hi, const std::string& unit, bool openLow) {
  const std::string range = (openLow ? "(" : "[") + formatNumber("%g", lo) + ", " + formatNumber("%g", hi) + "]" + (unit.empty() ? "" : " " + unit);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double v = 0.0;
        std::size_t used = 0;
        try {
          v = std::stod(text, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        const bool inside = used == text.size() && std::isfinite(v) && (openLow ? v > lo : v >= lo) && v <= hi;
        return inside ? std::string() : "must be a number in " + range + ", got '" + text + "'";
      },
      "NUMBER in " + range);
}

CLI::Validator integerIn(std::int64_t lo, std::int64_t hi, const std::string& unit) {
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]" + (unit.empty() ? "" : " " + unit);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        long long v = 0;
        std::size_t used = 0;
        try {
          v = std::stoll(text, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        const bool inside = used == text.size() && !text.empty() && v >= lo && v <= hi;
        return inside ? std::string() : "must be an integer in " + range + ", got '" + text + "'";
      },
      "INTEGER in " + range);
}

std::int64_t physicalMemoryMb() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGE_SIZE);
  std::int64_t mb = pages > 0 && pageSize > 0 ? std::int64_t(pages) * std::int64_t(pageSize) >> 20 : std::int64_t(1) << 20;
  struct rlimit limit {};
  if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
    mb = std::min<std::int64_t>(mb, std::int64_t(limit.rlim_cur >> 20));
  std::ifstream cgroup("/sys/fs/cgroup/memory.max");
  std::string text;
  if (cgroup >> text && text != "max") {
    try {
      mb = std::min<std::int64_t>(mb, std::int64_t(std::stoull(text) >> 20));
    } catch (const std::exception&) {
    }
  }
  return std::max<std::int64_t>(mb, 1);
}

std::int64_t checkGridFitsMemory(const std::string& path, std::int64_t maxMemoryMb, GridMemoryCost cost, const std::string& work,
                                 const std::string& hint) {
  const std::int64_t voxels = openGridSlices(path)->geometry().voxelCount();
  const auto needMb = std::int64_t(std::ceil(double(voxels) * cost.bytesPerVoxel / double(1 << 20))) + cost.fixedMb;
  const bool given = maxMemoryMb > 0;
  const std::int64_t budgetMb = given ? maxMemoryMb : physicalMemoryMb();
  if (needMb > budgetMb)
    throw InputError(path, withThousands(std::uint64_t(voxels)) + " voxels need about " + withThousands(std::uint64_t(needMb)) +
                               " MB to " + work + ", over the " + withThousands(std::uint64_t(budgetMb)) + " MB " +
                               (given ? "budget (--max-memory)" : "this machine allows") + (hint.empty() ? "" : "; " + hint));
  return needMb;
}

std::string withThousands(std::uint64_t n) {
  std::string s = std::to_string(n);
  for (int i = int(s.size()) - 3; i > 0; i -= 3) s.insert(std::size_t(i), ",");
  return s;
}

}  // namespace vox::app
