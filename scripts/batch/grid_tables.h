#pragma once

#include <string>
#include <vector>

#include "scripts/batch/grid_job.h"

namespace mrslam::batch {

// Writes tables.md: paper B's layout (rows dynamism, columns speed), each cell the mean over the
// runs of that cell that finished (rows[j] is jobs[j]'s), and how ekf_ela does against ekf when
// both ran.
void WriteGridTables(const std::string& path, const std::vector<Job>& jobs, const std::vector<Row>& rows,
                     const std::vector<std::string>& filters, const GridAxes& axes, int runs, int frames, int particles,
                     double seconds, bool multi_process);

}  // namespace mrslam::batch
