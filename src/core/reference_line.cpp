#include "overtake/core/reference_line.hpp"

#include <cmath>
#include <limits>
#include <string>

namespace overtake::core {
namespace {

constexpr double kSampleSpacingM = 2.0;  // dense samples for the global search
constexpr double kMaxSamples = 1e6;
constexpr double kHintMaxOffsetM = 30.0;     // a hinted projection farther off is re-searched
constexpr double kHintMaxJumpM = 200.0;      // ... and so is one far from the hint
constexpr double kMinNormalAgreement = 0.5;  // cos 60 degrees
constexpr int kMaxNewtonIterations = 30;
constexpr double kNewtonMaxStepM = 20.0;
constexpr double kNewtonToleranceM = 1e-10;

/// A frame at a wrapped s without its heading (an atan2 most queries do not read), and the
/// derivative it would be taken from.
struct FrameParts {
  RoadFrame frame;
  Vec2 d1;
};

FrameParts frame_parts(const SplineSample& ex, const SplineSample& ey, double side) {
  const Vec2 d1{ex.d1, ey.d1};
  const Vec2 d2{ex.d2, ey.d2};
  const double speed = norm(d1);
  RoadFrame f;
  f.position = {ex.value, ey.value};
  f.tangent = (1.0 / speed) * d1;
  f.normal = side * right_of(f.tangent);
  f.curvature_1pm = cross(d1, d2) / (speed * speed * speed);
  f.ds_scale = speed;
  return {f, d1};
}

FrameParts frame_parts(const PiecewiseCubic& x, const PiecewiseCubic& y, double side, double s) {
  const std::size_t i = x.piece(s);
  return frame_parts(x.eval_piece(i, s), y.eval_piece(i, s), side);
}

}  // namespace

ReferenceLine::ReferenceLine(const Map& map, double smoothing_m3) : map_(map) {
  const auto& w = map.waypoints;
  std::vector<double> s, x, y;
  s.reserve(w.size());
  x.reserve(w.size());
  y.reserve(w.size());
  for (const Waypoint& p : w) {
    s.push_back(p.s_m);
    x.push_back(p.x_m);
    y.push_back(p.y_m);
  }
  start_s_m_ = w.empty() ? 0.0 : w.front().s_m;
  length_m_ = map.loop_length_m;
  if (!(smoothing_m3 >= 0.0) || !std::isfinite(smoothing_m3)) {
    throw MapError(map.source + ": the line's smoothing stiffness must be finite and >= 0");
  }
  auto fx = smoothing_m3 > 0.0 ? PiecewiseCubic::periodic_smoothing(s, x, length_m_, smoothing_m3)
                               : PiecewiseCubic::periodic(s, x, length_m_);
  auto fy = smoothing_m3 > 0.0 ? PiecewiseCubic::periodic_smoothing(s, y, length_m_, smoothing_m3)
                               : PiecewiseCubic::periodic(s, y, length_m_);
  if (!fx || !fy) {
    throw MapError(map.source + ": the waypoints do not make a closed loop (need 3 or more with " +
                   "increasing s and a positive loop length)");
  }
  x_ = std::move(*fx);
  y_ = std::move(*fy);

  // Which side the map's normals point to: the project measures d along them.
  double agreement = 0.0;
  for (const Waypoint& p : w) {
    const RoadFrame f = frame(p.s_m);
    agreement += dot(right_of(f.tangent), {p.dx, p.dy});
  }
  side_ = agreement >= 0.0 ? 1.0 : -1.0;
  for (std::size_t i = 0; i < w.size(); ++i) {
    const RoadFrame f = frame(w[i].s_m);
    const double c = dot(f.normal, {w[i].dx, w[i].dy});
    if (!(c >= kMinNormalAgreement)) {  // also refuses a NaN normal
      throw MapError(map.source + ": waypoint " + std::to_string(i + 1) +
                     " (s = " + std::to_string(w[i].s_m) + "): its normal is " +
                     std::to_string(static_cast<int>(
                         std::lround(std::acos(std::max(-1.0, c)) * 180.0 / 3.141592653589793))) +
                     " degrees off the road's; normals must point away from the divider");
    }
  }

  // The dense samples for the global search: a loop parse_map accepts needs at most 100,000;
  // a Map built by hand with an absurd length is refused rather than sampled.
  const double wanted = std::ceil(length_m_ / kSampleSpacingM);
  if (!(wanted >= 2.0) || wanted > kMaxSamples) {
    throw MapError(map.source + ": a loop of " + std::to_string(length_m_) +
                   " m cannot be sampled for the reference line (2 m apart, at most " +
                   std::to_string(static_cast<long>(kMaxSamples)) + " samples)");
  }
  const auto count = static_cast<std::size_t>(wanted);
  sample_s_.reserve(count);
  sample_xy_.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const double si = start_s_m_ + length_m_ * static_cast<double>(i) / static_cast<double>(count);
    sample_s_.push_back(si);
    sample_xy_.push_back(frame(si).position);
  }
}

double ReferenceLine::wrap_s(double s_m) const {
  // Most s are within the loop already. With the loop starting at 0 (as the built-in track
  // does), fmod and the sums below give such an s back unchanged, bit for bit, so they are
  // left out (0 itself goes the long way: -0 comes back as +0).
  if (start_s_m_ == 0.0 && s_m > 0.0 && s_m < length_m_) return s_m;
  double r = std::fmod(s_m - start_s_m_, length_m_);
  if (r < 0.0) r += length_m_;
  if (r >= length_m_) r = 0.0;
  return start_s_m_ + r;
}

double ReferenceLine::s_ahead(double from_s_m, double to_s_m) const {
  double diff = wrap_s(to_s_m) - wrap_s(from_s_m);
  if (diff > 0.5 * length_m_) diff -= length_m_;
  if (diff <= -0.5 * length_m_) diff += length_m_;
  return diff;
}

RoadFrame ReferenceLine::frame(double s_m) const {
  FrameParts p = frame_parts(x_, y_, side_, wrap_s(s_m));
  p.frame.heading_rad = std::atan2(p.d1.y, p.d1.x);
  return p.frame;
}

RoadFrame ReferenceLine::frame_without_heading(double s_m) const {
  return frame_parts(x_, y_, side_, wrap_s(s_m)).frame;
}

Vec2 ReferenceLine::to_cartesian(FrenetPoint p) const {
  return to_cartesian(sample(p.s_m), p.d_m);
}

double ReferenceLine::refine(Vec2 p, double s0) const {
  double s = wrap_s(s0);
  for (int it = 0; it < kMaxNewtonIterations; ++it) {
    const std::size_t i = x_.piece(s);
    const SplineSample ex = x_.eval_piece(i, s);
    const SplineSample ey = y_.eval_piece(i, s);
    const Vec2 r{ex.value, ey.value};
    const Vec2 d1{ex.d1, ey.d1};
    const Vec2 d2{ex.d2, ey.d2};
    const Vec2 off = p - r;
    const double g = dot(off, d1);                          // zero at the foot point
    double gp = -dot(d1, d1) + dot(off, d2);                // dg/ds, negative near a minimum
    double step = gp < -1e-12 ? -g / gp : g / dot(d1, d1);  // gradient step if not convex
    if (step > kNewtonMaxStepM) step = kNewtonMaxStepM;
    if (step < -kNewtonMaxStepM) step = -kNewtonMaxStepM;
    s = wrap_s(s + step);
    if (std::abs(step) < kNewtonToleranceM) break;
  }
  return s;
}

FrenetPoint ReferenceLine::to_frenet(Vec2 p, std::optional<double> s_hint_m) const {
  auto result_at = [&](double s) {
    const RoadFrame f = frame_parts(x_, y_, side_, wrap_s(s)).frame;
    return FrenetPoint{s, dot(p - f.position, f.normal)};
  };
  if (s_hint_m && std::isfinite(*s_hint_m)) {
    const FrenetPoint r = result_at(refine(p, *s_hint_m));
    if (std::abs(r.d_m) < kHintMaxOffsetM && std::abs(s_ahead(*s_hint_m, r.s_m)) < kHintMaxJumpM) {
      return r;
    }
  }
  std::size_t best = 0;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < sample_xy_.size(); ++i) {
    const double d2 = distance_sq(p, sample_xy_[i]);
    if (d2 < best_d2) {
      best_d2 = d2;
      best = i;
    }
  }
  return result_at(refine(p, sample_s_[best]));
}

double ReferenceLine::curvature_at(double s_m, double d_m) const {
  const RoadFrame f = frame_parts(x_, y_, side_, wrap_s(s_m)).frame;
  return f.curvature_1pm / (1.0 + side_ * f.curvature_1pm * d_m);
}

Vec2 ReferenceLine::velocity(FrenetPoint p, double s_dot, double d_dot) const {
  return velocity(sample(p.s_m), p.d_m, s_dot, d_dot);
}

double ReferenceLine::s_rate(FrenetPoint p, double speed_mps) const {
  // The hot path of traffic motion: the same as from frame(), without heading or tangent.
  return speed_mps / metres_per_s(sample(p.s_m), p.d_m);
}

ReferenceLine::Sample ReferenceLine::sample(double s_m) const {
  const double s = wrap_s(s_m);
  const std::size_t i = x_.piece(s);
  return {s, x_.eval_piece(i, s), y_.eval_piece(i, s)};
}

double ReferenceLine::metres_per_s(const Sample& at, double d_m) const {
  const SplineSample& ex = at.x;
  const SplineSample& ey = at.y;
  const double speed_sq = ex.d1 * ex.d1 + ey.d1 * ey.d1;
  const double speed = std::sqrt(speed_sq);
  const double curvature = (ex.d1 * ey.d2 - ey.d1 * ex.d2) / (speed_sq * speed);
  return speed * (1.0 + side_ * curvature * d_m);
}

Vec2 ReferenceLine::velocity(const Sample& at, double d_m, double s_dot, double d_dot) const {
  const RoadFrame f = frame_parts(at.x, at.y, side_).frame;
  const double along = f.ds_scale * (1.0 + side_ * f.curvature_1pm * d_m);
  return (s_dot * along) * f.tangent + d_dot * f.normal;
}

Vec2 ReferenceLine::to_cartesian(const Sample& at, double d_m) const {
  const RoadFrame f = frame_parts(at.x, at.y, side_).frame;
  return f.position + d_m * f.normal;
}

}  // namespace overtake::core
