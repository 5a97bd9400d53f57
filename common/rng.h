#pragma once

#include <cstdint>
#include <random>
#include <sstream>
#include <string>
#include <string_view>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "common/archive.h"

namespace mrslam::common {

// SplitMix64 finalizer: a good 64-bit mixing function for deriving independent streams.
inline std::uint64_t Mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Stream seed for (run seed, stream name): every process derives its stream from the run's seed
// and its own id, so one seed fixes a whole run (FNV-1a over the name, then mixed).
inline std::uint64_t StreamSeed(std::uint64_t seed, std::string_view stream) {
  std::uint64_t h = 1469598103934665603ULL;
  for (const char c : stream) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ULL;
  }
  return Mix64(seed ^ Mix64(h));
}

// A seeded random stream. Owns its engine; not thread-safe.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  Rng(std::uint64_t seed, std::string_view stream) : engine_(StreamSeed(seed, stream)) {}

  double Uniform(double lo = 0.0, double hi = 1.0) { return std::uniform_real_distribution<double>(lo, hi)(engine_); }
  int UniformInt(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(engine_); }
  double Normal(double mean = 0.0, double sd = 1.0) { return sd == 0.0 ? mean : mean + sd * normal_(engine_); }
  // A sample of N(0, cov) through the Cholesky factor (cov symmetric positive semidefinite).
  template <int N>
  Eigen::Matrix<double, N, 1> Gaussian(const Eigen::Matrix<double, N, N>& cov) {
    Eigen::Matrix<double, N, 1> z;
    for (int i = 0; i < N; ++i) z(i) = normal_(engine_);
    const Eigen::LDLT<Eigen::Matrix<double, N, N>> ldlt(cov);
    Eigen::Matrix<double, N, 1> d = ldlt.vectorD().cwiseMax(0.0).cwiseSqrt();
    Eigen::Matrix<double, N, 1> y = ldlt.matrixL() * (d.asDiagonal() * z);
    return ldlt.transpositionsP().transpose() * y;
  }
  std::mt19937_64& engine() { return engine_; }

  // The engine's and the normal distribution's state (the standard library's exact text form).
  void Io(Archive& ar) {
    std::string text;
    if (!ar.loading()) {
      std::ostringstream out;
      out << engine_ << ' ' << normal_;
      text = out.str();
    }
    ar(text);
    if (ar.loading()) {
      std::istringstream in(text);
      in >> engine_ >> normal_;
      if (!in) throw ArchiveError("archive: a random stream's state does not read back");
    }
  }

 private:
  std::mt19937_64 engine_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace mrslam::common
