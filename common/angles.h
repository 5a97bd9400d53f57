#pragma once

#include <cmath>

namespace mrslam::common {

constexpr double kPi = 3.14159265358979323846;

// Wraps an angle to (-pi, pi].
inline double WrapAngle(double angle_rad) {
  double a = std::fmod(angle_rad + kPi, 2.0 * kPi);
  if (a < 0.0) a += 2.0 * kPi;
  a -= kPi;  // now in [-pi, pi)
  return a == -kPi ? kPi : a;
}

inline double DegFromRad(double rad) { return rad * 180.0 / kPi; }
inline double RadFromDeg(double deg) { return deg * kPi / 180.0; }

}  // namespace mrslam::common
