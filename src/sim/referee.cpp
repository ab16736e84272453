#include "overtake/sim/referee.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>

namespace overtake::sim {
namespace {

constexpr std::size_t index_of(IncidentType t) {
  return static_cast<std::size_t>(t);
}

/// True when `d_m` lies strictly within `half_width_m` of a lane line between two lanes.
bool on_inner_line(double d_m, const core::RoadParams& road, double half_width_m) {
  if (road.lane_count < 2) return false;
  // The nearest inner line is the only candidate: if any inner line is within the band,
  // the nearest one is.
  const double k = std::clamp(std::round(d_m / road.lane_width_m), 1.0,
                              static_cast<double>(road.lane_count - 1));
  return std::abs(d_m - k * road.lane_width_m) < half_width_m;
}

/// The original's curvature of one block: over each three consecutive positions, 2 sin(turn)
/// / |third - first| (unsigned); a triple with a zero step counts 0, a reversal 10^6; the
/// sum divided by the number of triples.
constexpr double kReversalCurvature = 1e6;

double triple_curvature(core::Vec2 a, core::Vec2 b, core::Vec2 c) {
  const core::Vec2 r1 = b - a;
  const core::Vec2 r2 = c - b;
  const double n1 = core::norm(r1);
  const double n2 = core::norm(r2);
  if (n1 == 0.0 || n2 == 0.0) return 0.0;
  const double chord = core::norm(c - a);
  const double cos_turn = std::clamp(core::dot(r1, r2) / (n1 * n2), -1.0, 1.0);
  if (chord == 0.0 || cos_turn <= -1.0) return kReversalCurvature;
  const double sin_turn = std::abs(core::cross(r1, r2)) / (n1 * n2);
  return 2.0 * sin_turn / chord;
}

void require(bool ok, const char* what) {
  if (!ok) throw std::invalid_argument(std::string("Referee: ") + what);
}

}  // namespace

std::string_view to_string(IncidentType t) {
  switch (t) {
    case IncidentType::collision:
      return "collision";
    case IncidentType::speeding:
      return "speeding";
    case IncidentType::max_acceleration:
      return "max_acceleration";
    case IncidentType::max_jerk:
      return "max_jerk";
    case IncidentType::outside_lane:
      return "outside_lane";
  }
  return "unknown";
}

Referee::Referee(const RefereeParams& params, double step_s, const core::RoadParams& road)
    : p_(params), step_s_(step_s), road_(road) {
  require(step_s > 0.0, "step_s must be positive");
  require(p_.accel_block_steps >= 1, "referee.accel_block_steps must be at least 1");
  require(p_.jerk_group_blocks >= 1, "referee.jerk_group_blocks must be at least 1");
  require(p_.latch_steps >= 1, "referee.latch_steps must be at least 1");
  require(p_.strict_window_steps >= 1, "referee.strict_window_steps must be at least 1");
  require(road_.lane_width_m > 0.0, "road.lane_width_m must be positive");
  // A rubric block needs its positions, the strict jerk 3w + 1.
  const auto needed = static_cast<std::size_t>(
      std::max(std::max(3, 3 * p_.strict_window_steps + 1), p_.accel_block_steps));
  ring_.assign(std::bit_ceil(needed), core::Vec2{});
  ring_mask_ = ring_.size() - 1;
}

std::array<int, kIncidentTypeCount> Referee::counts() const {
  return counts_;
}

bool Referee::latched(IncidentType type) const {
  return step_ < latch_until_step_[index_of(type)];
}

core::Vec2 Referee::recent(long back) const {
  return ring_[(ring_head_ - static_cast<std::size_t>(back)) & ring_mask_];
}

void Referee::count(IncidentType type, const EgoFrame& f, double value) {
  const bool per_block = type == IncidentType::max_acceleration || type == IncidentType::max_jerk;
  if (!per_block && latched(type)) return;
  const bool collision = type == IncidentType::collision;
  incidents_.push_back({type, f.t_s, f.s_m, core::lane_of(f.d_m, road_), value,
                        collision ? f.collision : std::nullopt, collision ? f.contact : -1});
  latch_until_step_[index_of(type)] = step_ + p_.latch_steps;
  ++counts_[index_of(type)];
  incident_free_m_ = 0.0;
}

void Referee::forget_counts() {
  incidents_.clear();
  counts_ = {};
  peaks_ = {};
  distance_m_ = 0.0;
  incident_free_m_ = 0.0;
  best_incident_free_m_ = 0.0;
  exact_outside_lane_ = 0;
}

void Referee::observe(const EgoFrame& f) {
  // Distance, then the new position joins the ring.
  if (ring_filled_ > 0) {
    const double moved_m = std::sqrt(core::distance_sq(f.position, recent(0)));
    distance_m_ += moved_m;
    incident_free_m_ += moved_m;
    best_incident_free_m_ = std::max(best_incident_free_m_, incident_free_m_);
  }
  ring_head_ = (ring_head_ + 1) & ring_mask_;
  ring_[ring_head_] = f.position;
  if (ring_filled_ < static_cast<long>(ring_.size())) ++ring_filled_;

  peaks_.speed_mps = std::max(peaks_.speed_mps, f.speed_mps);

  // Per-step rules.
  if (f.collided_with) count(IncidentType::collision, f, static_cast<double>(*f.collided_with));
  if (f.speed_mps > p_.speed_limit_mps) count(IncidentType::speeding, f, f.speed_mps);
  if (outside_lane(f.d_m, straddle_steps_)) count(IncidentType::outside_lane, f, f.d_m);
  if (outside_lane(f.exact_d_m, exact_straddle_steps_) && step_ >= exact_latch_until_step_) {
    ++exact_outside_lane_;
    exact_latch_until_step_ = step_ + p_.latch_steps;
  }

  update_rubric(f);
  update_strict();
  ++step_;
}

bool Referee::outside_lane(double d_m, int& straddle) const {
  // CarAIControl: off the road counts at once (the band timer holds); in a line band the
  // timer runs, elsewhere it resets; more than straddle_max_steps in a band counts.
  if (d_m < p_.edge_margin_m || d_m > core::road_width_m(road_) - p_.edge_margin_m) return true;
  straddle = on_inner_line(d_m, road_, p_.line_band_half_width_m) ? straddle + 1 : 0;
  return straddle > p_.straddle_max_steps;
}

void Referee::update_rubric(const EgoFrame& f) {
  block_speed_sum_ += f.speed_mps;
  if (++block_fill_ < p_.accel_block_steps) return;

  // The block's positions are the newest accel_block_steps of the ring (it holds enough).
  const int n = p_.accel_block_steps;
  const long have = std::min<long>(ring_filled_, n);
  double curvature_sum = 0.0;
  for (long k = 0; k + 2 < have; ++k) {
    curvature_sum +=
        triple_curvature(recent(have - 1 - k), recent(have - 2 - k), recent(have - 3 - k));
  }
  const double mean_curvature = have > 2 ? curvature_sum / static_cast<double>(have - 2) : 0.0;
  const double block_s = n * step_s_;
  const double mean_speed = block_speed_sum_ / n;
  block_fill_ = 0;
  block_speed_sum_ = 0.0;
  const double prev_speed = prev_block_mean_speed_;
  prev_block_mean_speed_ = mean_speed;

  const double tangential = (mean_speed - prev_speed) / block_s;
  const double normal = mean_speed * mean_speed * mean_curvature;
  const double total = std::sqrt(tangential * tangential + normal * normal);
  peaks_.acceleration_mps2 = std::max(peaks_.acceleration_mps2, total);
  if (total >= p_.max_accel_mps2) count(IncidentType::max_acceleration, f, total);

  group_sum_ += total;
  if (++group_fill_ < p_.jerk_group_blocks) return;
  const double group_mean = group_sum_ / p_.jerk_group_blocks;
  group_fill_ = 0;
  group_sum_ = 0.0;
  const double prev_mean = prev_group_mean_;
  prev_group_mean_ = group_mean;

  const double jerk = std::abs(group_mean - prev_mean) / (p_.jerk_group_blocks * block_s);
  peaks_.jerk_mps3 = std::max(peaks_.jerk_mps3, jerk);
  if (jerk >= p_.max_jerk_mps3) count(IncidentType::max_jerk, f, jerk);
}

StrictFigures Referee::current_strict() const {
  StrictFigures out;
  const long w = p_.strict_window_steps;
  if (ring_filled_ < 2 * w + 1) return out;
  const double window_s = static_cast<double>(w) * step_s_;
  const core::Vec2 p0 = recent(0);
  const core::Vec2 p1 = recent(w);
  const core::Vec2 p2 = recent(2 * w);
  // The same expressions as update_strict, so that the figures equal the peaks' inputs.
  const core::Vec2 accel = (1.0 / (window_s * window_s)) * (p0 - 2.0 * p1 + p2);
  out.acceleration_mps2 = core::norm(p0 - 2.0 * p1 + p2) / (window_s * window_s);
  const core::Vec2 travel = p0 - p2;  // direction of travel at the window's centre
  const double travel_m = core::norm(travel);
  if (travel_m > 0.0) {
    const core::Vec2 along = (1.0 / travel_m) * travel;
    out.tangential_mps2 = core::dot(accel, along);
    out.normal_mps2 = std::abs(core::cross(along, accel));
  } else {
    out.normal_mps2 = out.acceleration_mps2;  // standing: no direction of travel
  }
  if (ring_filled_ < 3 * w + 1) return out;
  const core::Vec2 p3 = recent(3 * w);
  out.jerk_mps3 = core::norm(p0 - 3.0 * p1 + 3.0 * p2 - p3) / (window_s * window_s * window_s);
  return out;
}

void Referee::update_strict() {
  const long w = p_.strict_window_steps;
  if (ring_filled_ < 2 * w + 1) return;
  const double window_s = static_cast<double>(w) * step_s_;
  const core::Vec2 p0 = recent(0);
  const core::Vec2 p1 = recent(w);
  const core::Vec2 p2 = recent(2 * w);
  const double accel = core::norm(p0 - 2.0 * p1 + p2) / (window_s * window_s);
  peaks_.strict_acceleration_mps2 = std::max(peaks_.strict_acceleration_mps2, accel);
  if (ring_filled_ < 3 * w + 1) return;
  const core::Vec2 p3 = recent(3 * w);
  const double jerk = core::norm(p0 - 3.0 * p1 + 3.0 * p2 - p3) / (window_s * window_s * window_s);
  peaks_.strict_jerk_mps3 = std::max(peaks_.strict_jerk_mps3, jerk);
}

}  // namespace overtake::sim

namespace overtake::sim {

void archive_incident(core::StateArchive& ar, Incident& incident, int lanes) {
  ar.io_enum(incident.type, IncidentType::outside_lane, "incident type");
  ar.io(incident.t_s, "incident time");
  ar.io_metres(incident.s_m, "incident s");
  ar.io_range(incident.lane, -64, lanes + 64, "incident lane");
  ar.io(incident.value, "incident value");
  ar.io_optional(incident.collision, "collision class",
                 [](core::StateArchive& a, CollisionClass& c) {
                   a.io_enum(c.kind, CollisionKind::car_stopped, "collision kind");
                   a.io(c.at_fault, "at fault");
                 });
}

void Referee::link_contacts(std::span<const Contact> contacts) {
  for (Incident& i : incidents_) {
    if (i.type != IncidentType::collision) continue;
    i.contact = -1;
    for (std::size_t k = 0; k < contacts.size(); ++k) {
      const Contact& c = contacts[k];
      if (c.car_id == static_cast<int>(i.value) && i.t_s >= c.t_s - 1e-9 &&
          i.t_s <= c.end_t_s + 1e-9) {
        i.contact = static_cast<int>(k);
        break;
      }
    }
  }
}

void Referee::archive(core::StateArchive& ar) {
  // A run of a week at 50 steps per second counts fewer than this.
  constexpr std::size_t kMaxIncidents = 1U << 24U;
  ar.part("referee");
  const int lanes = road_.lane_count;
  ar.io_vector(incidents_, kMaxIncidents, "incidents",
               [lanes](core::StateArchive& a, Incident& i) { archive_incident(a, i, lanes); });
  ar.io(peaks_.speed_mps, "peak speed");
  ar.io(peaks_.acceleration_mps2, "peak acceleration");
  ar.io(peaks_.jerk_mps3, "peak jerk");
  ar.io(peaks_.strict_acceleration_mps2, "peak strict acceleration");
  ar.io(peaks_.strict_jerk_mps3, "peak strict jerk");
  ar.io(distance_m_, "distance");
  ar.io(incident_free_m_, "incident-free distance");
  ar.io(best_incident_free_m_, "best incident-free distance");
  for (long& l : latch_until_step_) ar.io(l, "latch");
  for (int& c : counts_) ar.io(c, "incident count");
  ar.io(step_, "step");
  ar.io_range(block_fill_, 0, p_.accel_block_steps, "block fill");
  ar.io_metres(block_speed_sum_, "block speed sum");
  ar.io_speed(prev_block_mean_speed_, "previous block speed");
  ar.io_range(group_fill_, 0, p_.jerk_group_blocks, "group fill");
  ar.io(group_sum_, "group sum");
  ar.io(prev_group_mean_, "previous group mean");
  ar.io(exact_outside_lane_, "exact outside of lane");
  ar.io(exact_latch_until_step_, "exact latch");
  ar.io(exact_straddle_steps_, "exact straddle steps");
  const std::size_t ring = ring_.size();
  ar.require(ar.io_length(ring, ring, "recent positions") == ring,
             "recent positions: another window (the referee's params differ)");
  for (core::Vec2& v : ring_) ar.io(v, "recent position");
  ar.io_range(ring_head_, 0, ring - 1, "ring head");
  ar.io_range(ring_filled_, 0, static_cast<long>(ring), "ring fill");
  ar.io(straddle_steps_, "straddle steps");
}

}  // namespace overtake::sim
