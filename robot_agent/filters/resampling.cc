#include "robot_agent/filters/resampling.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mrslam::robot_agent::filters {

std::vector<double> NormalizeLogWeights(std::vector<double>* log_weights) {
  std::vector<double>& lw = *log_weights;
  const int n = static_cast<int>(lw.size());
  std::vector<double> w(n, n > 0 ? 1.0 / n : 0.0);
  if (n == 0) return w;
  // A particle whose likelihood is undefined (NaN) has no weight.
  for (double& x : lw) {
    if (std::isnan(x)) x = -std::numeric_limits<double>::infinity();
  }
  const double max_lw = *std::max_element(lw.begin(), lw.end());
  if (!std::isfinite(max_lw)) {
    std::fill(lw.begin(), lw.end(), -std::log(static_cast<double>(n)));
    return w;
  }
  // log sum exp(lw) = max + log sum exp(lw - max).
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    w[i] = std::exp(lw[i] - max_lw);
    sum += w[i];
  }
  const double log_sum = max_lw + std::log(sum);
  for (int i = 0; i < n; ++i) {
    lw[i] -= log_sum;
    w[i] /= sum;
  }
  return w;
}

double EffectiveSampleSize(const std::vector<double>& weights) {
  double sum_sq = 0.0;
  for (const double w : weights) sum_sq += w * w;
  return sum_sq > 0.0 ? 1.0 / sum_sq : 0.0;
}

std::vector<int> SystematicResample(const std::vector<double>& weights, common::Rng* rng) {
  const int n = static_cast<int>(weights.size());
  std::vector<int> parents(n);
  if (n == 0) return parents;
  // In units of 1/N: positions u + j, cumulative N * sum(w).
  const double u = rng->Uniform(0.0, 1.0);
  double cumulative = n * weights[0];
  int i = 0;
  for (int j = 0; j < n; ++j) {
    const double position = u + j;
    while (position >= cumulative && i < n - 1) cumulative += n * weights[++i];
    parents[j] = i;
  }
  return parents;
}

}  // namespace mrslam::robot_agent::filters
