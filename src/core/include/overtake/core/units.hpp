#pragma once
// Unit conversions. SI inside the project; mph and degrees exist only at the protocol edge
// and in human-facing reports.

#include <cmath>
#include <numbers>

namespace overtake::core {

/// Miles per hour in one metre per second.
inline constexpr double kMphPerMps = 2.23693629;
/// Metres in one mile.
inline constexpr double kMetresPerMile = 1609.344;
inline constexpr double kPi = std::numbers::pi;

[[nodiscard]] constexpr double mph_to_mps(double mph) {
  return mph / kMphPerMps;
}
[[nodiscard]] constexpr double mps_to_mph(double mps) {
  return mps * kMphPerMps;
}
[[nodiscard]] constexpr double deg_to_rad(double deg) {
  return deg * kPi / 180.0;
}
[[nodiscard]] constexpr double rad_to_deg(double rad) {
  return rad * 180.0 / kPi;
}
[[nodiscard]] constexpr double metres_to_miles(double m) {
  return m / kMetresPerMile;
}

/// Wraps an angle to (-pi, pi].
[[nodiscard]] inline double wrap_angle_rad(double a) {
  // remainder is exact: within [-pi, pi] (a / 2 pi within [-1/2, 1/2], the tie going to the
  // even quotient 0) it returns `a` itself, and most angles wrapped are there already.
  if (!(std::abs(a) <= kPi)) a = std::remainder(a, 2.0 * kPi);
  return a <= -kPi ? a + 2.0 * kPi : a;
}

}  // namespace overtake::core
