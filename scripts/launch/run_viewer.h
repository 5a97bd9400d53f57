#pragma once

#include <atomic>
#include <chrono>
#include <string>

#include "scripts/launch/process_supervisor.h"
#include "scripts/launch/progress_monitor.h"
#include "scripts/launch/simulation_run.h"

// The live view of a run (mrslam_launch --view): mrslam_view beside the run's processes.
namespace mrslam::launch {

// Starts mrslam_view on the run's domain and port, as a process of its own: its end never fails
// the run, and it is stopped (its last frame sent) when this goes away.
class RunViewer {
 public:
  RunViewer(const RunArgs& run, int port, const std::string& log_path);
  ~RunViewer();
  RunViewer(const RunViewer&) = delete;
  RunViewer& operator=(const RunViewer&) = delete;

  // Waits until the monitor sees the viewer in the domain, then prints its address. Returns the
  // readers it adds to the run (the agents and world_sim then wait for it too, so that it sees
  // the whole run): 1 once it has joined; 0, with a warning, if it ended or did not join in time.
  int Join(ProgressMonitor* monitor, const std::atomic<bool>& stop);

 private:
  ProcessSupervisor process_;
  std::string log_path_;
};

// The viewer's address in its output ("http://127.0.0.1:PORT/"), empty if not there.
std::string ViewerAddress(const std::string& log_text);

}  // namespace mrslam::launch
