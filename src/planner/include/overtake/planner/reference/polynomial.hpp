#pragma once
// Jerk-minimising polynomials in time (Werling et al. 2010): a quintic that meets position,
// velocity and acceleration at both ends (lane changes, following a car, stopping), and a
// quartic that meets a velocity and acceleration at the end (speed keeping).

#include <array>

namespace overtake::planner::reference {

/// Value and first three time derivatives of a 1-D motion at one time.
struct Motion1d {
  double x = 0.0;
  double v = 0.0;
  double a = 0.0;
  double j = 0.0;
};

/// x(t) = c0 + c1 t + ... + c5 t^5 on [0, duration_s]. After its end the motion continues at
/// its end velocity (the generators below end with zero acceleration); before its start the
/// polynomial itself is used, which continues the start state smoothly.
struct Polynomial1d {
  std::array<double, 6> c{};
  double duration_s = 0.0;

  /// The polynomial itself at t (no extension). Inline: the planner samples it thousands of
  /// times a cycle.
  [[nodiscard]] Motion1d raw(double t) const {
    const auto& k = c;
    return {k[0] + t * (k[1] + t * (k[2] + t * (k[3] + t * (k[4] + t * k[5])))),
            k[1] + t * (2.0 * k[2] + t * (3.0 * k[3] + t * (4.0 * k[4] + t * 5.0 * k[5]))),
            2.0 * k[2] + t * (6.0 * k[3] + t * (12.0 * k[4] + t * 20.0 * k[5])),
            6.0 * k[3] + t * (24.0 * k[4] + t * 60.0 * k[5])};
  }
  /// The motion at t, continued at constant velocity after duration_s.
  [[nodiscard]] Motion1d at(double t) const {
    return t <= duration_s ? raw(t) : at(t, raw(duration_s));
  }
  /// The same, given `end` = raw(duration_s) (sampling a grid, it is worked out once).
  [[nodiscard]] Motion1d at(double t, const Motion1d& end) const {
    if (t <= duration_s) return raw(t);
    return {end.x + end.v * (t - duration_s), end.v, 0.0, 0.0};
  }
  /// Integral of the squared jerk over [0, duration_s] (units^2 / s^5).
  [[nodiscard]] double jerk_cost() const;
};

/// The quintic from (x0, v0, a0) to (x1, v1, a1) in `duration_s` (> 0).
[[nodiscard]] Polynomial1d quintic(double x0, double v0, double a0, double x1, double v1, double a1,
                                   double duration_s);

/// The quartic from (x0, v0, a0) to velocity v1 and acceleration a1 in `duration_s` (> 0),
/// its end position free.
[[nodiscard]] Polynomial1d quartic(double x0, double v0, double a0, double v1, double a1,
                                   double duration_s);

/// The jerk-limited braking profile: from (x0, v0, a0) the acceleration moves at `jerk` to
/// -brake (or less, when the speed is too low for that), is held, and returns to 0 at the
/// same jerk just as the speed reaches 0; then it stands. Before t = 0 the start state is
/// continued with the first piece's jerk.
class BrakingProfile {
 public:
  BrakingProfile() = default;
  /// `brake` and `jerk` must be positive.
  BrakingProfile(double x0, double v0, double a0, double brake, double jerk);
  [[nodiscard]] Motion1d at(double t) const;
  /// When it stands still.
  [[nodiscard]] double stop_time_s() const { return start_[3]; }
  /// Integral of the squared jerk until it stands.
  [[nodiscard]] double jerk_cost() const;

 private:
  // Pieces of constant jerk: piece i starts at start_[i] in state states_[i]; piece 3 stands.
  std::array<double, 4> start_{};
  std::array<Motion1d, 4> states_{};
};

}  // namespace overtake::planner::reference
