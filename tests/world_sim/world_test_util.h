#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/config/scenario_options.h"

namespace mrslam::world_sim::testing {

// Two-sided 99.9% standard normal quantile z_{0.9995}.
constexpr double kZ999 = 3.2905267314919;

// Chi-square quantile with k degrees of freedom by the Wilson-Hilferty approximation:
// q_p(k) ~ k (1 - 2/(9k) + z_p sqrt(2/(9k)))^3 (relative error < 1e-3 for k >= 50).
inline double ChiSquareQuantile(double k, double z_p) {
  const double a = 2.0 / (9.0 * k);
  return k * std::pow(1.0 - a + z_p * std::sqrt(a), 3.0);
}

// Checks that zero-mean residuals e_i have variance `variance`: sum e_i^2 / variance ~ chi2(n)
// must fall within the two-sided 99.9% interval.
inline ::testing::AssertionResult VarianceMatches(const std::vector<double>& residuals, double variance) {
  const double n = static_cast<double>(residuals.size());
  double sum_sq = 0.0;
  for (const double e : residuals) sum_sq += e * e;
  const double statistic = sum_sq / variance;
  const double lo = ChiSquareQuantile(n, -kZ999), hi = ChiSquareQuantile(n, kZ999);
  if (statistic >= lo && statistic <= hi) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "sum e^2 / var = " << statistic << " outside the 99.9% chi2(" << n
                                       << ") interval [" << lo << ", " << hi << "] (sample variance " << sum_sq / n
                                       << " vs " << variance << ")";
}

// Checks that samples of a quantity with standard deviation sd have mean `mean`:
// |mean_hat - mean| <= z_{0.9995} sd / sqrt(n).
inline ::testing::AssertionResult MeanMatches(const std::vector<double>& samples, double mean, double sd) {
  double sum = 0.0;
  for (const double s : samples) sum += s;
  const double n = static_cast<double>(samples.size());
  const double bound = kZ999 * sd / std::sqrt(n);
  if (std::abs(sum / n - mean) <= bound) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "sample mean " << sum / n << " differs from " << mean << " by more than "
                                       << bound;
}

// A quiet scenario: one robot "r1" standing at the origin facing +x, no landmarks, every
// noise zero, full field of view, 10 m range, identities reported.
inline common::ScenarioOptions QuietScenario() {
  common::ScenarioOptions o;
  o.name = "test";
  o.seed = 7;
  o.run.steps = 100;
  o.run.dt_s = 0.1;
  common::RobotOptions r;
  r.id = "r1";
  o.robots.push_back(r);
  o.sensors.lidar.max_range_m = 10.0;
  o.sensors.lidar.robot_detection_range_m = 10.0;
  o.sensors.lidar.range_noise_sd_m = 0.0;
  o.sensors.lidar.bearing_noise_sd_rad = 0.0;
  o.sensors.lidar.report_identity = true;
  o.sensors.imu.gyro_noise_sd_radps = 0.0;
  o.sensors.imu.accel_noise_sd_mps2 = 0.0;
  o.noise.robot_process_var.setZero();
  o.noise.landmark_process_var.setZero();
  return o;
}

inline common::LandmarkOptions StaticLandmark(int id, double x, double y) {
  common::LandmarkOptions l;
  l.id = id;
  l.pose = {x, y, 0.0};
  return l;
}

}  // namespace mrslam::world_sim::testing
