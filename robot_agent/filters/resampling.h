#pragma once

#include <vector>

#include "common/rng.h"

// Particle weights in the log domain and low-variance resampling.
namespace mrslam::robot_agent::filters {

// Normalizes log weights in place so that sum(exp(log_w)) = 1 (subtracting the log-sum-exp);
// returns the normalized linear weights. A NaN log weight (an undefined likelihood) counts as -inf;
// all -inf (every particle impossible) resets to uniform.
std::vector<double> NormalizeLogWeights(std::vector<double>* log_weights);

// Effective sample size 1 / sum(w_i^2) of normalized weights.
double EffectiveSampleSize(const std::vector<double>& weights);

// Low-variance (systematic) resampling: N draws at positions (u + j) / N, u ~ U[0, 1), over the
// cumulative weights; returns the index of the parent of each new particle, ascending. Equal
// weights keep every particle exactly once.
std::vector<int> SystematicResample(const std::vector<double>& weights, common::Rng* rng);

}  // namespace mrslam::robot_agent::filters
