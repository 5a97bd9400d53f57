#include "scripts/batch/slip_recovery.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/angles.h"
#include "scripts/batch/batch_report.h"
#include "scripts/batch/filter_accuracy.h"
#include "world_sim/evaluator/metrics.h"

namespace mrslam::batch {
namespace {

// Steps after the first landmark reading that follows a slip at which recovery is judged, and
// the bounds it must meet then.
constexpr int kRecoverySteps = 30;
constexpr double kErrorRatio = 2.0;
constexpr double kHeadingDeg = 5.0;

// One robot's run, step by step (index k - 1 for step k).
struct Trace {
  std::vector<double> position_err_m, heading_err_deg;
  std::vector<bool> saw_landmark;
};

// Runs one seed with each robot's own filter and records every robot's errors.
std::vector<Trace> RunTraces(const common::ScenarioOptions& options, std::uint64_t seed) {
  std::vector<Trace> traces(options.robots.size());
  ScoreSeed(options, seed, Estimators::kOwnFilter,
            [&](std::size_t i, const common::SensorStep& step, const evaluator::StepScore& s) {
              traces[i].position_err_m.push_back(s.position_err_m);
              traces[i].heading_err_deg.push_back(common::DegFromRad(s.heading_err_rad));
              traces[i].saw_landmark.push_back(!step.lidar.landmarks.empty());
            });
  return traces;
}

// A slipping robot's outcome in one seed.
struct Outcome {
  int judged_step = 0;  // 0: no landmark reading after the slip
  double error_m = std::nan(""), reference_error_m = std::nan(""), heading_err_deg = std::nan("");
  bool recovered = false;
};

Outcome Judge(const Trace& slipped, const Trace& reference, int slip_step) {
  Outcome out;
  const int steps = static_cast<int>(slipped.saw_landmark.size());
  int reading = slip_step + 1;
  while (reading <= steps && !slipped.saw_landmark[static_cast<std::size_t>(reading - 1)]) ++reading;
  if (reading > steps) return out;
  out.judged_step = std::min(reading + kRecoverySteps, steps);
  const auto at = static_cast<std::size_t>(out.judged_step - 1);
  out.error_m = slipped.position_err_m[at];
  out.reference_error_m = reference.position_err_m[at];
  out.heading_err_deg = std::abs(slipped.heading_err_deg[at]);
  out.recovered = out.error_m < kErrorRatio * out.reference_error_m && out.heading_err_deg <= kHeadingDeg;
  return out;
}

}  // namespace

int PrintSlipRecovery(const common::ScenarioOptions& options, std::uint64_t first_seed, int num_seeds, int threads,
                      const std::string& json_path) {
  std::vector<int> slipping;  // robots with a slip, and each one's first slip
  std::vector<int> first_slip;
  for (std::size_t i = 0; i < options.robots.size(); ++i) {
    const auto& slips = options.robots[i].slips;
    if (slips.empty()) continue;
    slipping.push_back(static_cast<int>(i));
    first_slip.push_back(std::min_element(slips.begin(), slips.end(), [](const auto& a, const auto& b) {
                           return a.step < b.step;
                         })->step);
  }
  if (slipping.empty()) throw std::runtime_error("--slip-recovery: no robot of the scenario slips (robots[].slips)");
  common::ScenarioOptions without = options;
  for (auto& r : without.robots) r.slips.clear();
  std::vector<std::vector<Outcome>> outcomes(static_cast<std::size_t>(num_seeds));
  ForEachSeed(num_seeds, threads, [&](int s) {
    const std::vector<Trace> slipped = RunTraces(options, first_seed + s);
    const std::vector<Trace> reference = RunTraces(without, first_seed + s);
    for (std::size_t r = 0; r < slipping.size(); ++r) {
      const auto i = static_cast<std::size_t>(slipping[r]);
      outcomes[static_cast<std::size_t>(s)].push_back(Judge(slipped[i], reference[i], first_slip[r]));
    }
  });
  nlohmann::json json = StartReport(options, first_seed, num_seeds, options.filter.type + ", recovery from slips");
  std::printf("medians at the judged step (the first landmark reading after the slip + %d steps)\n", kRecoverySteps);
  std::printf("%-6s %10s %20s %20s %20s\n", "robot", "recovered", "error [m]", "without slip [m]",
              "heading error [deg]");
  for (std::size_t r = 0; r < slipping.size(); ++r) {
    const std::string& id = options.robots[static_cast<std::size_t>(slipping[r])].id;
    std::vector<double> error, reference, heading;
    std::vector<int> steps;
    int recovered = 0;
    for (const auto& seed : outcomes) {
      const Outcome& o = seed[r];
      recovered += o.recovered ? 1 : 0;
      steps.push_back(o.judged_step);
      error.push_back(o.error_m);
      reference.push_back(o.reference_error_m);
      heading.push_back(o.heading_err_deg);
    }
    std::printf("%-6s %6d/%-3d %20.3f %20.3f %20.2f\n", id.c_str(), recovered, num_seeds, evaluator::Median(error),
                evaluator::Median(reference), evaluator::Median(heading));
    json["robots"][id] = {
        {"slip_step", first_slip[r]},        {"recovered", recovered},      {"judged_step", steps}, {"error_m", error},
        {"error_without_slip_m", reference}, {"heading_error_deg", heading}};
  }
  WriteJson(json, json_path);
  return 0;
}

}  // namespace mrslam::batch
