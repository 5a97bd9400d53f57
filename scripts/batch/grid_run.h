#pragma once

#include "common/config/scenario_options.h"
#include "scripts/batch/grid_job.h"

// Running one of mrslam_grid's jobs and scoring it by paper B's metrics (evaluator::PaperBScorer).
namespace mrslam::batch {

// In-process: the World and one filter per robot. The oracle (kOracle) is the ekf given the
// static landmarks' detections only.
Row RunJob(const common::ScenarioOptions& base, const Job& job, int frames);

// As separate processes: world_sim and one robot_agent per robot on a free DDS domain, in
// lockstep, started and supervised as the launcher does (scripts/launch/simulation_run.h); this
// process reads the truth and the estimates over DDS and scores them like an in-process run.
Row RunJobMultiProcess(const common::ScenarioOptions& base, const MultiProcessSetup& setup, const Job& job, int frames);

}  // namespace mrslam::batch
