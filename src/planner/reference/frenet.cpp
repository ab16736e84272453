#include "overtake/planner/reference/frenet.hpp"

#include <algorithm>
#include <cmath>

#include "overtake/core/map.hpp"
#include "overtake/core/waypoint_frenet.hpp"

namespace overtake::planner::reference {
namespace {

/// The chord reading is sampled in the middle of the road every metre of s, averaged over
/// the local waypoint spacing, then twice over this to round it off ...
constexpr double kRoundOffM = 25.0;
/// ... and drawn through knots this far apart.
constexpr double kKnotSpacingM = 5.0;

/// Centred moving average of a periodic sequence, over `width[i]` samples at sample i.
std::vector<double> moving_average(const std::vector<double>& v, const std::vector<double>& width) {
  const std::size_t n = v.size();
  std::vector<double> prefix(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) prefix[i + 1] = prefix[i] + v[i];
  const auto sum = [&](long a, long b) {  // sum of v[a .. b) with wrapping, b - a <= n
    const auto ln = static_cast<long>(n);
    double total = 0.0;
    while (a < 0) {
      a += ln;
      b += ln;
    }
    if (b <= ln) return prefix[static_cast<std::size_t>(b)] - prefix[static_cast<std::size_t>(a)];
    total = prefix[n] - prefix[static_cast<std::size_t>(a)];
    return total + prefix[static_cast<std::size_t>(b - ln)];
  };
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    const long half = std::max(1L, std::lround(0.5 * width[i]));
    const long a = static_cast<long>(i) - half;
    const long b = static_cast<long>(i) + half + 1;
    out[i] = sum(a, b) / static_cast<double>(b - a);
  }
  return out;
}

}  // namespace

LaneFrame::LaneFrame(const core::ReferenceLine& line) : line_(&line) {}

LaneFrame LaneFrame::chord_aligned(const core::ReferenceLine& line, const core::RoadParams& road) {
  LaneFrame f(line);
  const double sample_d = 0.5 * core::road_width_m(road);
  // The chords between the map's waypoints as given (the line may pass beside them).
  const core::Map& map = line.map();
  if (map.waypoints.size() < 3) return f;
  const core::WaypointFrenet chords(map);
  const auto bins = static_cast<std::size_t>(std::ceil(line.length_m()));
  std::vector<double> reading(bins);
  std::vector<double> spacing(bins);
  std::size_t hint = 0;
  for (std::size_t b = 0; b < bins; ++b) {
    const double s = line.start_s_m() + static_cast<double>(b);
    const core::Vec2 p = line.to_cartesian({s, sample_d});
    hint = chords.closest(p, hint);
    reading[b] = chords.to_frenet(p, hint).d_m - sample_d;
    const std::size_t next = chords.next(p, hint);
    const std::size_t prev = chords.wrap_index(static_cast<long>(next) - 1);
    spacing[b] = core::distance(chords.position(prev), chords.position(next));
  }
  const std::vector<double> round_off(bins, kRoundOffM);
  const std::vector<double> smooth =
      moving_average(moving_average(moving_average(reading, spacing), round_off), round_off);
  std::vector<double> knots;
  std::vector<double> values;
  const auto every = static_cast<std::size_t>(kKnotSpacingM);
  for (std::size_t b = 0; b + every / 2 < bins; b += every) {
    knots.push_back(line.start_s_m() + static_cast<double>(b));
    values.push_back(smooth[b]);
  }
  f.offset_ = core::PiecewiseCubic::periodic(knots, values, line.length_m());
  f.reading_ = std::move(reading);
  return f;
}

LaneFrame::Reading LaneFrame::reading(double s_m) const {
  if (!offset_ || reading_.empty()) return {};
  double x = std::fmod(s_m - line_->start_s_m(), line_->length_m());
  if (x < 0.0) x += line_->length_m();
  const auto i = static_cast<std::size_t>(x);
  const double f = x - static_cast<double>(i);
  const std::size_t n = reading_.size();
  const double raw = reading_[i % n] * (1.0 - f) + reading_[(i + 1) % n] * f;
  return {true, offset(s_m), raw};
}

LaneFrame::OffsetSlope LaneFrame::offset_slope(double s_m) const {
  if (!offset_) return {};
  const core::SplineSample o = offset_->eval(line_->wrap_s(s_m));
  return {o.value, o.d1};
}

double LaneFrame::offset(double s_m) const {
  if (!offset_) return 0.0;
  return (*offset_)(line_->wrap_s(s_m));
}

double LaneFrame::slope(double s_m) const {
  if (!offset_) return 0.0;
  return offset_->eval(line_->wrap_s(s_m)).d1;
}

RoadPoint road_point(const LaneFrame& frame, double s_m, double d_m) {
  return road_point(frame.line().frame_without_heading(s_m), frame.offset_slope(s_m), d_m);
}

RoadPoint road_point(const core::RoadFrame& f, const LaneFrame::OffsetSlope& o, double d_m) {
  const double d_line = d_m - o.offset_m;
  // +1 when the normal points to the right of travel; the line's curvature-at-offset rule
  // depends on it.
  const double side = core::dot(f.normal, core::right_of(f.tangent)) >= 0.0 ? 1.0 : -1.0;
  const double stretch = 1.0 + side * f.curvature_1pm * d_line;
  RoadPoint p;
  p.position = f.position + d_line * f.normal;
  p.tangent = f.tangent;
  p.normal = f.normal;
  p.along_scale = f.ds_scale * stretch;
  p.curvature_1pm = f.curvature_1pm / stretch;
  p.offset_slope = o.slope;
  return p;
}

FrenetState frenet_from_cartesian(const LaneFrame& frame, core::Vec2 position, core::Vec2 velocity,
                                  double s_hint_m, RoadPoint* at_out) {
  const core::FrenetPoint f = frame.line().to_frenet(position, s_hint_m);
  const LaneFrame::OffsetSlope o = frame.offset_slope(f.s_m);
  const double d = f.d_m + o.offset_m;
  const RoadPoint at = road_point(frame.line().frame_without_heading(f.s_m), o, d);
  if (at_out) *at_out = at;
  FrenetState x;
  x.s_m = f.s_m;
  x.d_m = d;
  x.s_dot = at.along_scale > 1e-9 ? core::dot(velocity, at.tangent) / at.along_scale : 0.0;
  x.d_dot_mps = core::dot(velocity, at.normal) + at.offset_slope * x.s_dot;
  return x;
}

}  // namespace overtake::planner::reference
