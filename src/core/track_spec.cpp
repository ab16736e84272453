// Track specs: their limits, their validation, and the messages that name a field.

#include "overtake/core/track.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "overtake/core/road.hpp"
#include "track_internal.hpp"

namespace overtake::core {
namespace {

// ---- Limits (metres unless named otherwise) ----

constexpr double kMinLoopLengthM = 1000.0;
constexpr double kMaxLoopLengthM = 200000.0;
constexpr double kMinLengthPerMinRadius = 24.0;   // room for four corners and a right bend
constexpr double kMinSpacingRatio = 1.2;          // max_spacing_m / min_spacing_m, to generate
constexpr double kMaxMinSpacingPerRadius = 0.25;  // min_spacing_m / min_radius_m, to generate
constexpr double kSmallLoopLengthM = 7500.0;      // loops up to this fit the default box
constexpr double kSmallLoopMaxCoordinateM = 1000.0;
constexpr double kMaxStartStraightFraction = 0.1;  // of the loop

[[noreturn]] void bad_field(const std::string& field, const std::string& why) {
  throw std::invalid_argument("TrackSpec." + field + ": " + why);
}

void require_finite(double v, const char* field) {
  if (!std::isfinite(v)) bad_field(field, "must be finite (got " + std::to_string(v) + ")");
}

}  // namespace

namespace track_detail {

std::string num(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

void validate_check_spec(const TrackSpec& spec) {
  require_finite(spec.length_m, "length_m");
  require_finite(spec.min_radius_m, "min_radius_m");
  require_finite(spec.min_spacing_m, "min_spacing_m");
  require_finite(spec.max_spacing_m, "max_spacing_m");
  require_finite(spec.min_clearance_m, "min_clearance_m");
  require_finite(spec.shoulder_m, "shoulder_m");
  require_finite(spec.max_abs_coordinate_m, "max_abs_coordinate_m");
  require_finite(spec.start_straight_m, "start_straight_m");
  require_finite(spec.straight_spacing_m, "straight_spacing_m");
  require_finite(spec.bend_radius_m, "bend_radius_m");
  require_finite(spec.road.lane_width_m, "road.lane_width_m");
  if (!(spec.length_m > 0.0)) bad_field("length_m", "must be positive");
  if (!(spec.min_radius_m > 0.0)) bad_field("min_radius_m", "must be positive");
  if (!(spec.min_spacing_m > 0.0)) bad_field("min_spacing_m", "must be positive");
  if (!(spec.min_spacing_m < spec.max_spacing_m)) {
    bad_field("min_spacing_m", "must be below max_spacing_m (" + num(spec.min_spacing_m) +
                                   " >= " + num(spec.max_spacing_m) + ")");
  }
  if (spec.min_clearance_m < 0.0) bad_field("min_clearance_m", "must not be negative");
  if (spec.shoulder_m < 0.0) bad_field("shoulder_m", "must not be negative");
  if (spec.max_abs_coordinate_m < 0.0) {
    bad_field("max_abs_coordinate_m", "must not be negative (0 picks the default)");
  }
  if (spec.start_straight_m < 0.0) bad_field("start_straight_m", "must not be negative");
  if (!(spec.straight_spacing_m > 0.0)) bad_field("straight_spacing_m", "must be positive");
  if (!(spec.bend_radius_m > 0.0)) bad_field("bend_radius_m", "must be positive");
  if (spec.road.lane_count < 1) bad_field("road.lane_count", "must be at least 1");
  if (!(spec.road.lane_width_m > 0.0)) bad_field("road.lane_width_m", "must be positive");
}

double required_start_straight_m(const TrackSpec& spec) {
  return std::min(spec.start_straight_m, kMaxStartStraightFraction * spec.length_m);
}

}  // namespace track_detail

using track_detail::num;

void validate_track_spec(const TrackSpec& spec) {
  track_detail::validate_check_spec(spec);
  if (spec.length_m < kMinLoopLengthM) {
    bad_field("length_m", "must be at least " + num(kMinLoopLengthM, 0) + " m (got " +
                              num(spec.length_m) + ")");
  }
  if (spec.length_m > kMaxLoopLengthM) {
    bad_field("length_m",
              "must be at most " + num(kMaxLoopLengthM, 0) + " m (got " + num(spec.length_m) + ")");
  }
  if (spec.length_m < kMinLengthPerMinRadius * spec.min_radius_m) {
    bad_field("length_m", "a loop of " + num(spec.length_m) + " m has no room for bends of " +
                              "min_radius_m = " + num(spec.min_radius_m) + " m (it needs " +
                              num(kMinLengthPerMinRadius, 0) + " times that)");
  }
  if (spec.min_spacing_m > kMaxMinSpacingPerRadius * spec.min_radius_m) {
    bad_field("min_spacing_m",
              "waypoints " + num(spec.min_spacing_m) +
                  " m apart cannot follow bends of min_radius_m = " + num(spec.min_radius_m) +
                  " m (at most " + num(kMaxMinSpacingPerRadius * spec.min_radius_m) + " m)");
  }
  if (spec.max_spacing_m < kMinSpacingRatio * spec.min_spacing_m) {
    bad_field("max_spacing_m", "must be at least " + num(kMinSpacingRatio) +
                                   " times min_spacing_m to place waypoints");
  }
  const double box = max_abs_coordinate_for(spec) - road_width_m(spec.road) - spec.shoulder_m;
  if (8.0 * box < spec.length_m) {
    bad_field("max_abs_coordinate_m", "a box of +-" + num(max_abs_coordinate_for(spec)) +
                                          " m is too small for a loop of " + num(spec.length_m) +
                                          " m");
  }
}

double max_abs_coordinate_for(const TrackSpec& spec) {
  if (spec.max_abs_coordinate_m > 0.0) return spec.max_abs_coordinate_m;
  return kSmallLoopMaxCoordinateM * std::max(1.0, spec.length_m / kSmallLoopLengthM);
}

}  // namespace overtake::core
