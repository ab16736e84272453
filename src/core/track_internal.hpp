#pragma once
// What the track files share (track_spec.cpp, track_course.cpp, track_generate.cpp,
// track_check.cpp); not part of the core's interface (overtake/core/track.hpp is).

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/track.hpp"

namespace overtake::core::track_detail {

// ---- The spec (track_spec.cpp) ----

/// `v` with `decimals` decimals, for messages.
[[nodiscard]] std::string num(double v, int decimals = 1);

/// What checking needs of a spec (generating needs more: validate_track_spec). Throws
/// std::invalid_argument naming the field.
void validate_check_spec(const TrackSpec& spec);

/// The straight road a map must start with: the spec's, capped at a share of the loop.
[[nodiscard]] double required_start_straight_m(const TrackSpec& spec);

// ---- The shape: a curvature profile (track_course.cpp) ----

// A stretch of road whose curvature changes linearly along it: a straight, an arc or a
// clothoid.
struct Piece {
  double length_m = 0.0;
  double k0_1pm = 0.0;  // curvature at the start, positive to the left
  double k1_1pm = 0.0;  // at the end
};

struct Pose {
  Vec2 position;
  double heading_rad = 0.0;
};

/// Pose at `u1` metres into the piece, from the pose `at` at `u0` metres: exact heading,
/// position by composite three-point Gauss-Legendre quadrature.
[[nodiscard]] Pose advance(const Piece& p, const Pose& at, double u0, double u1);

// The closed course: pieces laid end to end from the origin, heading along +x.
class Course {
 public:
  explicit Course(std::vector<Piece> pieces);

  [[nodiscard]] double length_m() const { return starts_.back(); }
  [[nodiscard]] const Pose& end() const { return poses_.back(); }
  [[nodiscard]] Pose pose_at(double s) const;
  [[nodiscard]] double curvature_at(double s) const;
  // Smallest box around the divider line: {min corner, max corner}.
  [[nodiscard]] std::pair<Vec2, Vec2> bounds() const;

 private:
  [[nodiscard]] std::size_t piece_at(double s) const;

  std::vector<Piece> pieces_;
  std::vector<double> starts_;  // s of each piece's start, then the total
  std::vector<Pose> poses_;     // pose at each piece's start, then at the end
};

}  // namespace overtake::core::track_detail
