#include "scripts/batch/grid_tables.h"

#include <algorithm>
#include <fstream>
#include <functional>
#include <map>
#include <ostream>
#include <stdexcept>
#include <tuple>
#include <utility>

#include <fmt/format.h>

namespace mrslam::batch {
namespace {

using evaluator::MeanOfFinite;

// tables.md: paper B's layout (rows dynamism, columns speed), each cell the mean over the runs of
// that cell that finished, and how ekf_ela does against ekf when both ran.
class GridTables {
 public:
  GridTables(const std::vector<Job>& jobs, const std::vector<Row>& rows, std::vector<std::string> filters,
             GridAxes axes)
      : axes_(std::move(axes)), filters_(std::move(filters)), jobs_(jobs.size()) {
    for (std::size_t j = 0; j < jobs.size(); ++j) {
      num_robots_ = std::max(num_robots_, rows[j].robot_rmse_per_robot_m.size());
      if (rows[j].failed) {
        ++failed_;
        continue;
      }
      cells_[{jobs[j].filter, jobs[j].dynamism_index, jobs[j].speed_index}].push_back(&rows[j]);
    }
    for (std::size_t f = 0; f < filters_.size(); ++f) filter_names_ += (f ? " / " : "") + filters_[f];
  }

  void Write(const std::string& path, int runs, int frames, int particles, double seconds, bool multi_process) const {
    std::ofstream out(path);
    if (!out) throw std::runtime_error("cannot write " + path);
    out << "# Paper B's grid (" << (multi_process ? "multi-process" : "in-process") << ")\n\n";
    out << "Means over " << runs << " runs (seeds 1.." << runs << ") of " << frames
        << " frames, 3 robots; rows: dynamism (share of moving landmarks), columns: landmark speed (m/s). "
        << "fastslam with constant_turn_rate tracking and " << particles << " particles. ";
    out << fmt::format("Wall time of the grid: {:.0f} s.", seconds);
    if (failed_ > 0) out << " " << failed_ << " of " << jobs_ << " runs failed and are left out of the means.";
    out << "\n\n";
    WriteMetricTables(out);
    const bool have_pair =
        std::count(filters_.begin(), filters_.end(), "ekf") && std::count(filters_.begin(), filters_.end(), "ekf_ela");
    if (have_pair) WriteTargets(out);
  }

 private:
  using CellKey = std::tuple<std::string, int, int>;
  struct Metric {
    const char* title;
    double Row::*field;
  };

  // The runs of (filter, cell) that finished.
  const std::vector<const Row*>& Cell(const std::string& f, int d, int s) const {
    static const std::vector<const Row*> kNone;
    const auto it = cells_.find({f, d, s});
    return it == cells_.end() ? kNone : it->second;
  }
  double MeanOf(const std::string& f, int d, int s, double Row::*field) const {
    std::vector<double> v;
    for (const Row* r : Cell(f, d, s)) v.push_back(r->*field);
    return MeanOfFinite(v);
  }
  // One markdown table: rows dynamism, columns speed, cell(d, s) as text.
  void Table(std::ostream& out, const std::string& heading, const std::function<std::string(int, int)>& cell) const {
    out << "## " << heading << "\n\n| dynamism |";
    for (const double sp : axes_.speeds) out << fmt::format(" {:.1f} m/s |", sp);
    out << "\n|---|";
    for (std::size_t sp = 0; sp < axes_.speeds.size(); ++sp) out << "---|";
    out << "\n";
    for (std::size_t d = 0; d < axes_.dynamism.size(); ++d) {
      out << fmt::format("| {:.0f} % |", 100.0 * axes_.dynamism[d]);
      for (std::size_t sp = 0; sp < axes_.speeds.size(); ++sp) {
        out << " " << cell(static_cast<int>(d), static_cast<int>(sp)) << " |";
      }
      out << "\n";
    }
    out << "\n";
  }
  // "a / b / c" over the filters.
  std::string PerFilter(const std::function<double(const std::string&)>& value) const {
    std::string text;
    for (std::size_t f = 0; f < filters_.size(); ++f)
      text += fmt::format("{}{:.2f}", f ? " / " : "", value(filters_[f]));
    return text;
  }

  // The metrics' tables over the filters, then paper B's per-robot position RMSE (its tables 2-4).
  void WriteMetricTables(std::ostream& out) const {
    const Metric metrics[] = {{"Total landmark RMSE (m), eqs. 17-18", &Row::landmark_rmse_m},
                              {"Robot position RMSE (m), mean over robots", &Row::robot_rmse_m},
                              {"Static-landmark completeness at the end", &Row::static_completeness},
                              {"Static-landmark completeness at the end, map points assigned among the static "
                               "landmarks only",
                               &Row::static_only_completeness}};
    for (const auto& m : metrics) {
      Table(out, std::string(m.title) + ": " + filter_names_,
            [&](int d, int sp) { return PerFilter([&](const std::string& f) { return MeanOf(f, d, sp, m.field); }); });
    }
    for (std::size_t robot = 0; robot < num_robots_; ++robot) {
      Table(out, "Position RMSE (m) of robot " + std::to_string(robot + 1) + ": " + filter_names_, [&](int d, int sp) {
        return PerFilter([&](const std::string& f) {
          std::vector<double> v;
          for (const Row* r : Cell(f, d, sp)) v.push_back(r->robot_rmse_per_robot_m[robot]);
          return MeanOfFinite(v);
        });
      });
    }
  }

  // The ratios ekf_ela / ekf and how many cells meet each target.
  void WriteTargets(std::ostream& out) const {
    const Metric ratios[] = {{"Ratio ekf_ela / ekf, landmark RMSE", &Row::landmark_rmse_m},
                             {"Ratio ekf_ela / ekf, robot RMSE", &Row::robot_rmse_m}};
    for (const auto& m : ratios) {
      Table(out, m.title, [&](int d, int sp) {
        return fmt::format("{:.2f}", MeanOf("ekf_ela", d, sp, m.field) / MeanOf("ekf", d, sp, m.field));
      });
    }
    int lm_better = 0, robot_better = 0, ratio_ok = 0, ratio_cells = 0, completeness_ok = 0;
    for (std::size_t d = 0; d < axes_.dynamism.size(); ++d) {
      for (std::size_t s = 0; s < axes_.speeds.size(); ++s) {
        const int di = static_cast<int>(d), si = static_cast<int>(s);
        const double lm =
            MeanOf("ekf_ela", di, si, &Row::landmark_rmse_m) / MeanOf("ekf", di, si, &Row::landmark_rmse_m);
        if (lm < 1.0) ++lm_better;
        if (MeanOf("ekf_ela", di, si, &Row::robot_rmse_m) < MeanOf("ekf", di, si, &Row::robot_rmse_m)) ++robot_better;
        if (axes_.dynamism[d] >= 0.35 - 1e-9) {
          ++ratio_cells;
          if (lm <= 0.6) ++ratio_ok;
        }
        if (MeanOf("ekf_ela", di, si, &Row::static_completeness) >=
            MeanOf("ekf", di, si, &Row::static_completeness) - 0.05) {
          ++completeness_ok;
        }
      }
    }
    const int total = static_cast<int>(axes_.dynamism.size() * axes_.speeds.size());
    const int at_least = total - total / 10;  // 27 of 30
    out << "## ekf_ela against ekf (targets), on the means above\n\n";
    out << "- ekf_ela better than ekf on landmark RMSE: " << lm_better << "/" << total << " cells (target " << total
        << ")\n";
    out << "- ekf_ela better than ekf on robot RMSE: " << robot_better << "/" << total
        << " cells (target >= " << at_least << ")\n";
    out << "- ekf_ela landmark RMSE <= 0.6 of ekf's at dynamism >= 35 %: " << ratio_ok << "/" << ratio_cells
        << " cells\n";
    out << "- ekf_ela static completeness at most 0.05 below ekf's: " << completeness_ok << "/" << total << " cells\n";
  }

  GridAxes axes_;
  std::vector<std::string> filters_;
  std::string filter_names_;
  std::size_t jobs_ = 0, failed_ = 0, num_robots_ = 0;
  std::map<CellKey, std::vector<const Row*>> cells_;
};

}  // namespace

void WriteGridTables(const std::string& path, const std::vector<Job>& jobs, const std::vector<Row>& rows,
                     const std::vector<std::string>& filters, const GridAxes& axes, int runs, int frames, int particles,
                     double seconds, bool multi_process) {
  GridTables(jobs, rows, filters, axes).Write(path, runs, frames, particles, seconds, multi_process);
}

}  // namespace mrslam::batch
