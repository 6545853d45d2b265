#pragma once
// The viewer's export: deformGrid (what `voxmorph deform` runs) with the
// pose being edited, on a worker thread. The progress sink is process-wide;
// only the worker's reports move the bar, and a cancel request ends the
// worker at its next report (the writers are atomic, so no partial file is
// left).

#include "geometry/deform/run/deform_run.h"

#include <atomic>
#include <mutex>
#include <string>
#include <thread>

namespace vox {
class PoseEditor;
}

namespace vox::app {

// An output path whose directory exists and takes new files (checked before
// the work that writes it). Throws InputError(path, ...).
void checkWritablePath(const std::string& path);

// The request for the editor's pose of the grid file `grid` (organ table
// file `organs`, for the provenance), to be written to `output` with its
// report at `report` ("" for none): checked, with its provenance, and its
// output paths checked. Throws what the checks throw.
DeformGridRequest exportRequest(const PoseEditor& editor, const std::string& grid, const std::string& organs,
                                     const std::string& output, const std::string& report, bool preserveVolumes);

class ExportJob {
public:
  ~ExportJob();
  bool running() const { return running_; }
  // Starts the export (the previous one must have ended); the report is
  // written to reportPath unless it is empty.
  void start(DeformGridRequest request, std::string reportPath);
  void cancel() { cancel_ = true; }
  void wait();
  double fraction() const { return fraction_; }
  std::string stage() const;
  // How the last export ended ("exported PATH", "export cancelled; ...",
  // "export failed: ..."); empty before the first one ends.
  std::string message() const;

private:
  std::thread thread_;
  std::atomic<bool> running_{false}, cancel_{false};
  std::atomic<double> fraction_{0.0};
  mutable std::mutex mutex_;
  std::string stage_, message_;
};

}  // namespace vox::app
