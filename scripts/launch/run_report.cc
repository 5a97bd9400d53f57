#include "scripts/launch/run_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <utility>

#include "world_sim/evaluator/metrics.h"

namespace mrslam::launch {

namespace {

using nlohmann::json;

std::string Number(const json& value, int decimals) {
  if (!value.is_number()) return "-";
  const double v = value.get<double>();
  if (!std::isfinite(v)) return "-";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, v);
  return buffer;
}

std::string Field(const json& object, const char* key, int decimals) {
  if (!object.is_object() || !object.contains(key)) return "-";
  return Number(object.at(key), decimals);
}

std::string JoinStrings(const json& list) {
  if (!list.is_array() || list.empty()) return "-";
  std::string out;
  for (const auto& item : list) {
    if (!out.empty()) out += ",";
    out += item.is_string() ? item.get<std::string>() : item.dump();
  }
  return out;
}

std::string Rendezvous(const json& list) {
  if (!list.is_array() || list.empty()) return "-";
  std::string out;
  for (const auto& event : list) {
    if (!out.empty()) out += "; ";
    const std::string peer =
        event.contains("peer") && event["peer"].is_string() ? event["peer"].get<std::string>() : "?";
    out += peer + "@" + Field(event, "step", 0) + " (" + Field(event, "transform_error_m", 3) + " m, " +
           Field(event, "transform_error_deg", 2) + " deg)";
  }
  return out;
}

// Columns padded to their widest cell: text columns (left[c]) left-aligned, numbers right-aligned.
std::string Render(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows,
                   const std::vector<bool>& left) {
  std::vector<std::size_t> width(header.size(), 0);
  for (std::size_t c = 0; c < header.size(); ++c) width[c] = header[c].size();
  for (const auto& row : rows) {
    for (std::size_t c = 0; c < row.size() && c < width.size(); ++c) width[c] = std::max(width[c], row[c].size());
  }
  auto line = [&](const std::vector<std::string>& cells) {
    std::string out;
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const std::string pad(width[c] - cells[c].size(), ' ');
      if (c > 0) out += "  ";
      out += left[c] ? cells[c] + (c + 1 == cells.size() ? "" : pad) : pad + cells[c];
    }
    return out + "\n";
  };
  std::string out = line(header);
  for (const auto& row : rows) out += line(row);
  return out;
}

}  // namespace

const std::vector<std::string>& AggregatedMetrics() {
  static const std::vector<std::string> metrics = {"position_rmse_m",
                                                   "heading_rmse_deg",
                                                   "landmark_rmse_m",
                                                   "static_landmark_rmse_m",
                                                   "moving_landmark_rmse_m",
                                                   "own_landmark_rmse_m",
                                                   "adopted_landmark_nees",
                                                   "dead_reckoning_rmse_m",
                                                   "map_completeness",
                                                   "moving_completeness",
                                                   "union_completeness",
                                                   "reachable_union_completeness",
                                                   "static_reachable_union_completeness",
                                                   "common_landmarks_within_3sd",
                                                   "mean_nees",
                                                   "final_trajectory_rmse_m",
                                                   "final_heading_rmse_deg",
                                                   "step_cpu_ms_median"};
  return metrics;
}

std::string SummaryTable(const json& summary) {
  const std::vector<std::string> header = {"robot",
                                           "position RMSE [m]",
                                           "heading RMSE [deg]",
                                           "landmark RMSE [m]",
                                           "dead reckoning RMSE [m]",
                                           "landmarks mapped",
                                           "map completeness",
                                           "frames known",
                                           "rendezvous (peer@step, transform error)"};
  std::vector<std::vector<std::string>> rows;
  if (summary.contains("robots") && summary["robots"].is_object()) {
    for (const auto& [id, r] : summary["robots"].items()) {
      rows.push_back({id, Field(r, "position_rmse_m", 3), Field(r, "heading_rmse_deg", 2),
                      Field(r, "landmark_rmse_m", 3), Field(r, "dead_reckoning_rmse_m", 3),
                      Field(r, "landmarks_mapped", 0), Field(r, "map_completeness", 2),
                      r.contains("frames_known") ? JoinStrings(r["frames_known"]) : "-",
                      r.contains("rendezvous") ? Rendezvous(r["rendezvous"]) : "-"});
    }
  }
  return Render(header, rows, {true, false, false, false, false, false, false, true, true});
}

std::vector<std::string> RejectionWarnings(const json& summary, const std::string& log_dir) {
  std::vector<std::string> out;
  if (!summary.contains("robots") || !summary["robots"].is_object()) return out;
  for (const auto& [id, r] : summary["robots"].items()) {
    const json rejected = r.value("rejected_samples", json());
    if (!rejected.is_number_unsigned() || rejected.get<std::uint64_t>() == 0) continue;
    std::string line = "warning: ";
    line.append(id)
        .append("'s agent rejected ")
        .append(rejected.dump())
        .append(" samples or peer messages (malformed, stale, or from another run on the same DDS domain); see ")
        .append(log_dir)
        .append("/robot_agent_")
        .append(id)
        .append(".log");
    out.push_back(std::move(line));
  }
  return out;
}

json Aggregate(const std::vector<json>& summaries, const std::vector<long long>& seeds) {
  json out;
  out["scenario"] = summaries.empty() ? json() : summaries.front().value("scenario", json());
  out["seeds"] = seeds;
  out["runs"] = summaries.size();
  json robots = json::object();
  // Robot ids in the order of the first summary, then any others.
  std::vector<std::string> ids;
  for (const auto& s : summaries) {
    if (!s.contains("robots") || !s["robots"].is_object()) continue;
    for (const auto& [id, unused] : s["robots"].items()) {
      (void)unused;
      if (std::find(ids.begin(), ids.end(), id) == ids.end()) ids.push_back(id);
    }
  }
  for (const auto& id : ids) {
    json per_metric = json::object();
    for (const auto& metric : AggregatedMetrics()) {
      std::vector<double> values;
      json listed = json::array();
      for (const auto& s : summaries) {
        const json* v = nullptr;
        if (s.contains("robots") && s["robots"].contains(id) && s["robots"][id].contains(metric)) {
          v = &s["robots"][id][metric];
        }
        if (v != nullptr && v->is_number() && std::isfinite(v->get<double>())) {
          values.push_back(v->get<double>());
          listed.push_back(v->get<double>());
        } else {
          listed.push_back(nullptr);
        }
      }
      json m;
      m["median"] = values.empty() ? json() : json(evaluator::Median(values));
      m["p90"] = values.empty() ? json() : json(evaluator::Percentile(values, 90.0));
      m["values"] = listed;
      per_metric[metric] = m;
    }
    robots[id] = per_metric;
  }
  out["robots"] = robots;
  return out;
}

std::string AggregateTable(const json& aggregate) {
  const std::vector<std::string> header = {"robot", "metric", "median", "p90"};
  std::vector<std::vector<std::string>> rows;
  if (aggregate.contains("robots") && aggregate["robots"].is_object()) {
    for (const auto& [id, metrics] : aggregate["robots"].items()) {
      for (const auto& metric : AggregatedMetrics()) {
        if (!metrics.contains(metric)) continue;
        const int decimals = metric == "heading_rmse_deg" ? 2 : 3;
        rows.push_back(
            {id, metric, Field(metrics[metric], "median", decimals), Field(metrics[metric], "p90", decimals)});
      }
    }
  }
  return Render(header, rows, {true, true, false, false});
}

}  // namespace mrslam::launch
