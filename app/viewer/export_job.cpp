#include "app/viewer/export_job.h"

#include "app/command_line.h"
#include "geometry/atomic_file.h"
#include "geometry/deform/pose/pose_editor.h"
#include "geometry/deform/report/deformation_report.h"
#include "geometry/error.h"
#include "geometry/progress.h"
#include "gpu/raster_engines.h"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include <unistd.h>

namespace vox::app {

void checkWritablePath(const std::string& path) {
  const std::filesystem::path p(path);
  const std::filesystem::path dir = p.has_parent_path() ? p.parent_path() : std::filesystem::path(".");
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) throw InputError(path, "its directory does not exist");
  const std::filesystem::path probe = dir / (".voxmorph-write-test-" + std::to_string(::getpid()));
  std::ofstream out(probe);
  if (!out) throw InputError(path, "its directory is not writable");
  out.close();
  std::filesystem::remove(probe, ec);
}

DeformGridRequest exportRequest(const PoseEditor& editor, const std::string& grid, const std::string& organs,
                                     const std::string& output, const std::string& report, bool preserveVolumes) {
  DeformGridRequest request;
  request.input = grid;
  request.output = output;
  request.pose = editor.pose();
  request.poseSource = "view";
  request.organs = editor.organs();
  request.preserveVolumes = preserveVolumes;
  request.warn = [](const std::string& m) { std::fprintf(stderr, "view: warning: %s\n", m.c_str()); };
  checkDeformGridRequest(request);
  request.provenance = commandProvenance({{"grid", grid}, {"organs", organs}});
  addTextInput(request.provenance, "pose", "edited in the viewer (grid frame, as poseToJson writes it)", poseToJson(request.pose));
  checkWritablePath(output);
  if (!report.empty()) checkWritablePath(report);
  return request;
}

namespace {
struct ExportCancelled {};
}  // namespace

ExportJob::~ExportJob() {
  cancel();
  if (thread_.joinable()) thread_.join();
  setProgressSink(nullptr);
}

void ExportJob::start(DeformGridRequest request, std::string reportPath) {
  if (thread_.joinable()) thread_.join();
  cancel_ = false;
  running_ = true;
  fraction_ = 0.0;
  {
    std::lock_guard lock(mutex_);
    stage_ = "starting";
    message_.clear();
  }
  thread_ = std::thread([this, request = std::move(request), reportPath = std::move(reportPath)] {
    const std::thread::id me = std::this_thread::get_id();
    setProgressSink([this, me](std::string_view stage, double fraction) {
      if (std::this_thread::get_id() != me) return;
      if (cancel_) throw ExportCancelled{};
      fraction_ = fraction;
      std::lock_guard lock(mutex_);
      stage_ = std::string(stage);
    });
    std::string message;
    try {
      const DeformationReport report = deformGrid(request, *gpu::makeRasterEngines(false, request.warn));
      if (!reportPath.empty()) writeFileAtomic(reportPath, deformationReportJson(report));
      message = "exported " + request.output;
    } catch (const ExportCancelled&) {
      message = "export cancelled; nothing written";
    } catch (const std::exception& e) {
      message = std::string("export failed: ") + e.what();
    }
    setProgressSink(nullptr);
    {
      std::lock_guard lock(mutex_);
      message_ = message;
    }
    running_ = false;
  });
}

void ExportJob::wait() {
  if (thread_.joinable()) thread_.join();
}

std::string ExportJob::stage() const {
  std::lock_guard lock(mutex_);
  return stage_;
}

std::string ExportJob::message() const {
  std::lock_guard lock(mutex_);
  return message_;
}

}  // namespace vox::app
