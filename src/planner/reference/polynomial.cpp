#include "overtake/planner/reference/polynomial.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace overtake::planner::reference {
namespace {

/// The state after `dt` of constant jerk from `m`.
Motion1d advance(const Motion1d& m, double dt) {
  return {m.x + dt * (m.v + dt * (0.5 * m.a + dt * m.j / 6.0)), m.v + dt * (m.a + 0.5 * dt * m.j),
          m.a + dt * m.j, m.j};
}

}  // namespace

double Polynomial1d::jerk_cost() const {
  // jerk = a + b t + g t^2
  const double a = 6.0 * c[3];
  const double b = 24.0 * c[4];
  const double g = 60.0 * c[5];
  const double t = duration_s;
  return t * (a * a + t * (a * b + t * ((b * b + 2.0 * a * g) / 3.0 +
                                        t * (0.5 * b * g + t * g * g / 5.0))));
}

Polynomial1d quintic(double x0, double v0, double a0, double x1, double v1, double a1,
                     double duration_s) {
  assert(duration_s > 0.0);
  const double t = duration_s;
  const double t2 = t * t;
  const double t3 = t2 * t;
  const double dx = x1 - (x0 + v0 * t + 0.5 * a0 * t2);
  const double dv = v1 - (v0 + a0 * t);
  const double da = a1 - a0;
  Polynomial1d p;
  p.duration_s = t;
  p.c = {x0,
         v0,
         0.5 * a0,
         (10.0 * dx - 4.0 * dv * t + 0.5 * da * t2) / t3,
         (-15.0 * dx + 7.0 * dv * t - da * t2) / (t3 * t),
         (6.0 * dx - 3.0 * dv * t + 0.5 * da * t2) / (t3 * t2)};
  return p;
}

Polynomial1d quartic(double x0, double v0, double a0, double v1, double a1, double duration_s) {
  assert(duration_s > 0.0);
  const double t = duration_s;
  const double dv = v1 - (v0 + a0 * t);
  const double da = a1 - a0;
  Polynomial1d p;
  p.duration_s = t;
  p.c = {x0,
         v0,
         0.5 * a0,
         (3.0 * dv - da * t) / (3.0 * t * t),
         (da * t - 2.0 * dv) / (4.0 * t * t * t),
         0.0};
  return p;
}

BrakingProfile::BrakingProfile(double x0, double v0, double a0, double brake, double jerk) {
  assert(brake > 0.0 && jerk > 0.0);
  Motion1d m{x0, std::max(0.0, v0), a0, 0.0};
  if (m.v <= 0.0) {
    m.a = 0.0;
    states_.fill(m);
    start_.fill(0.0);
    return;
  }
  // The deepest deceleration p such that ramping a0 -> -p and -p -> 0 at `jerk` stops the
  // car: (a0^2 - 2 p^2) / (2 jerk) = -v0 when a0 > -p.
  double peak = brake;
  const double needed = std::sqrt(std::max(0.0, 0.5 * (a0 * a0 + 2.0 * jerk * m.v)));
  if (needed < peak) peak = needed;
  double release_jerk = jerk;
  double t = 0.0;
  // Piece 0: towards -peak.
  m.j = a0 > -peak ? -jerk : jerk;
  double d0 = std::abs(a0 + peak) / jerk;
  if (a0 < -peak) {
    // Already braking harder than the stop needs: release at once, at the jerk that stops
    // the car exactly as the acceleration reaches zero.
    d0 = 0.0;
    release_jerk = a0 * a0 / (2.0 * m.v);
  }
  states_[0] = m;
  start_[0] = t;
  m = advance(m, d0);
  t += d0;
  // Piece 1: hold until the release can end at standstill.
  m.j = 0.0;
  const double a_hold = std::min(m.a, 0.0);
  m.a = a_hold;
  const double release_dv = a_hold * a_hold / (2.0 * release_jerk);
  const double d1 = a_hold < 0.0 ? std::max(0.0, (m.v - release_dv) / -a_hold) : 0.0;
  states_[1] = m;
  start_[1] = t;
  m = advance(m, d1);
  t += d1;
  // Piece 2: release.
  m.j = release_jerk;
  const double d2 = -a_hold / release_jerk;
  states_[2] = m;
  start_[2] = t;
  m = advance(m, d2);
  t += d2;
  states_[3] = {m.x, 0.0, 0.0, 0.0};
  start_[3] = t;
}

double BrakingProfile::jerk_cost() const {
  double cost = 0.0;
  for (std::size_t i = 0; i < 3; ++i)
    cost += states_[i].j * states_[i].j * (start_[i + 1] - start_[i]);
  return cost;
}

Motion1d BrakingProfile::at(double t) const {
  if (t < 0.0) return advance(states_[0], t);
  int i = 3;
  while (i > 0 && t < start_[static_cast<std::size_t>(i)]) --i;
  const auto k = static_cast<std::size_t>(i);
  if (i == 3) return states_[3];
  Motion1d m = advance(states_[k], t - start_[k]);
  m.v = std::max(0.0, m.v);
  return m;
}

}  // namespace overtake::planner::reference
