#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

// Turning the evaluator's summary.json files into tables and the seeds' aggregate.
namespace mrslam::launch {

// The per-robot metrics that aggregate.json summarizes over seeds.
const std::vector<std::string>& AggregatedMetrics();

// A fixed-width table of a summary.json: one row per robot with position, heading, landmark and
// dead-reckoning RMSE, landmarks mapped, map completeness, frames known and rendezvous (peer,
// step and transform error). Missing or null values print as "-".
std::string SummaryTable(const nlohmann::json& summary);

// One warning per robot whose agent rejected samples or peer messages (summary.json's
// rejected_samples: malformed, stale, or sent by another run on the same DDS domain, which
// would also have fed it foreign data), naming its log in log_dir; empty when none did.
std::vector<std::string> RejectionWarnings(const nlohmann::json& summary, const std::string& log_dir);

// aggregate.json from the summaries of several seeds (same scenario):
//   {"scenario", "seeds": [...], "runs": n,
//    "robots": {"r1": {"position_rmse_m": {"median", "p90", "values": [...]}, ...}}}
// median and p90 (90th percentile, numpy's linear rule) over the seeds that have a finite value;
// null when none has.
nlohmann::json Aggregate(const std::vector<nlohmann::json>& summaries, const std::vector<long long>& seeds);

// A fixed-width table of an aggregate: one row per robot and metric with median and p90.
std::string AggregateTable(const nlohmann::json& aggregate);

}  // namespace mrslam::launch
