#include "overtake/sim/safety.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "overtake/sim/traffic.hpp"

namespace overtake::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// lane_since: not in that lane / in it since before the run or the body's placement.
constexpr long kNotIn = -1;
constexpr long kAlways = std::numeric_limits<long>::min();
/// A body that moves further than this along the road in one step was placed anew (faithful
/// traffic re-places cars far from the ego), not driven.
constexpr double kTeleportM = 30.0;
/// The ego moves toward a lane when its d changed by more than kAcrossM over kDirectionSteps.
constexpr long kDirectionSteps = 10;
constexpr double kAcrossM = 0.02;

/// s from `from_s` to `to_s` on a loop of `loop_m`, in (-loop/2, loop/2].
double wrap_delta(double from_s, double to_s, double loop_m) {
  double ds = to_s - from_s;
  if (loop_m <= 0.0) return ds;
  // s lies within one loop, so one subtraction or addition does (fmod, far slower, is for
  // anything else).
  if (ds >= loop_m || ds <= -loop_m) ds = std::fmod(ds, loop_m);
  if (ds > 0.5 * loop_m) ds -= loop_m;
  if (ds <= -0.5 * loop_m) ds += loop_m;
  return ds;
}

}  // namespace

std::string_view to_string(CollisionKind kind) {
  switch (kind) {
    case CollisionKind::ego_hit_car_ahead:
      return "ego_hit_car_ahead";
    case CollisionKind::hit_from_behind:
      return "hit_from_behind";
    case CollisionKind::hit_from_behind_braking:
      return "hit_from_behind_braking";
    case CollisionKind::ego_lane_change:
      return "ego_lane_change";
    case CollisionKind::car_cut_in:
      return "car_cut_in";
    case CollisionKind::side_contact:
      return "side_contact";
    case CollisionKind::ego_stopped:
      return "ego_stopped";
    case CollisionKind::car_stopped:
      return "car_stopped";
  }
  return "unknown";
}

double time_to_collision_s(double gap_m, double follower_speed_mps, double leader_speed_mps) {
  const double closing_mps = follower_speed_mps - leader_speed_mps;
  if (!(closing_mps > 0.0)) return kInf;
  return std::max(gap_m, 0.0) / closing_mps;
}

bool entry_absorbable(const LaneEntry& e, double front_speed_now_mps, double loop_length_m,
                      const core::CarFootprint& size, const SafetyParams& p) {
  const double ds = wrap_delta(e.ego.s_m, e.car.s_m, loop_length_m);
  const double gap_m = std::abs(ds) - size.length_m;
  if (gap_m <= 0.0) return false;  // it came in beside the other
  const double rear_mps = std::max(0.0, ds > 0.0 ? e.ego_speed_mps : e.car_speed_mps);
  const double front_mps = std::max(0.0, ds > 0.0 ? e.car_speed_mps : e.ego_speed_mps);
  const double b = p.hard_braking_mps2;
  // What the one ahead did: its mean deceleration from the entry to the contact.
  const double since_s = std::max(e.entered_s_ago, 1e-3);
  const double front_decel = (front_mps - std::max(0.0, front_speed_now_mps)) / since_s;
  if (front_decel > b) return false;
  // The one behind responding properly against it: the least gap over time, piecewise
  // quadratic, sampled finely until the one behind has stopped (the gap only grows after).
  const double t_r = p.reaction_time_s;
  const double t_end = t_r + rear_mps / b;
  const auto travelled = [](double v, double decel, double t) {
    if (decel > 0.0) t = std::min(t, v / decel);  // it stops
    return v * t - 0.5 * decel * t * t;
  };
  constexpr int kSamples = 2000;
  for (int i = 1; i <= kSamples; ++i) {
    const double t = t_end * static_cast<double>(i) / kSamples;
    const double rear_m =
        rear_mps * std::min(t, t_r) + travelled(rear_mps, b, std::max(0.0, t - t_r));
    if (gap_m + travelled(front_mps, front_decel, t) - rear_m <= 0.0) return false;
  }
  return true;
}

CollisionClass classify_collision(const ContactSituation& s, const SafetyParams& p) {
  using K = CollisionKind;
  // Which way they met: along the axis on which they were apart just before (the larger of
  // the two gaps, bumper to bumper and side to side).
  const double ds = wrap_delta(s.ego.frenet.s_m, s.car.frenet.s_m, s.loop_length_m);
  const double dd = s.car.frenet.d_m - s.ego.frenet.d_m;
  const double along_gap_m = std::abs(ds) - s.size.length_m;
  const double across_gap_m = std::abs(dd) - s.size.width_m;
  const bool side_by_side = across_gap_m > along_gap_m;
  const bool car_ahead = !side_by_side && ds > 0.0;
  const bool car_behind = !side_by_side && !car_ahead;
  const bool ego_braked_hard = s.ego_deceleration_mps2 > p.hard_braking_mps2;

  // Standing still first, as nuPlan does: an ego that stands is not at fault, a car that
  // stands is hit by the ego. An ego that came to a stand by braking harder than traffic does,
  // in front of a car that then ran into it, is judged as the same stop at a crawl is (below).
  if (s.ego.speed_mps <= p.stopped_speed_mps && !(car_behind && ego_braked_hard)) {
    return {K::ego_stopped, false};
  }
  if (s.car.speed_mps <= p.stopped_speed_mps) return {K::car_stopped, true};

  if (side_by_side) {
    if (s.ego.in_two_lanes && !s.car.in_two_lanes) return {K::ego_lane_change, true};
    if (s.car.in_two_lanes && !s.ego.in_two_lanes) return {K::car_cut_in, false};
    // Both in one lane (one wandered) or both changing: the fault of the one that moved
    // more toward the other.
    return {K::side_contact, s.ego.toward_other_m > s.car.toward_other_m};
  }

  // Front or rear. The more recent entry into the other's lane within the window decides
  // first: whoever entered made the situation, unless the one behind could have absorbed it.
  const double window = p.lane_change_window_s;
  const bool ego_entered = s.ego_entry.s_ago < window;
  const bool car_entered = s.car_entry.s_ago < window;
  const bool ego_entered_last =
      ego_entered && (!car_entered || s.ego_entry.s_ago <= s.car_entry.s_ago);
  if (ego_entered_last) {
    // Into a car ahead: always the ego's. In front of a follower: the ego's when the
    // follower could not absorb the gap it was left.
    if (car_ahead || !entry_absorbable(s.ego_entry, s.ego.speed_mps, s.loop_length_m, s.size, p)) {
      return {K::ego_lane_change, true};
    }
  } else if (car_entered) {
    // Into the ego's rear: the car's. In front of the ego: the car's when the ego could not
    // absorb it, else the ego had room to brake.
    if (!car_ahead || !entry_absorbable(s.car_entry, s.car.speed_mps, s.loop_length_m, s.size, p)) {
      return {K::car_cut_in, false};
    }
    return {K::ego_hit_car_ahead, true};
  }
  if (car_ahead) return {K::ego_hit_car_ahead, true};
  // A follower in a lane the ego did not just enter drove into its rear (nuPlan's active rear
  // collision, also when the ego's body reaches into the next lane): not the ego's, unless it
  // braked harder than traffic does.
  if (ego_braked_hard) return {K::hit_from_behind_braking, true};
  return {K::hit_from_behind, false};
}

SafetyMonitor::SafetyMonitor(const SafetyParams& params, double step_s,
                             const core::RoadParams& road, const core::CarFootprint& size,
                             double loop_length_m)
    : p_(params), step_s_(step_s), road_(road), size_(size), loop_length_m_(loop_length_m) {
  if (!(step_s > 0.0)) throw std::invalid_argument("SafetyMonitor: step_s must be positive");
  if (road.lane_count < 1 || road.lane_count > static_cast<int>(ego_.lane_since.size())) {
    throw std::invalid_argument("SafetyMonitor: road.lane_count must be 1-" +
                                std::to_string(ego_.lane_since.size()));
  }
  window_steps_ = std::max<long>(1, std::lround(p_.braking_window_s / step_s));
  contact_gap_steps_ = std::max<long>(1, std::lround(p_.contact_gap_s / step_s));
  inverse_lane_width_ = 1.0 / road_.lane_width_m;
  summary_.ttc_threshold_s = p_.ttc_threshold_s;
  summary_.headway_threshold_s = p_.headway_threshold_s;
}

std::pair<int, int> SafetyMonitor::lane_span(double d_m) const {
  // Lane l (from l w to (l + 1) w) holds at least m of the body [d - W/2, d + W/2] when
  // l w <= d + W/2 - m and (l + 1) w >= d - W/2 + m (given W >= m and w >= m).
  const double half = 0.5 * size_.width_m;
  const double m = p_.lane_overlap_m;
  if (size_.width_m < m) return {0, -1};
  // Clamped to a little beyond the road first, so that the integer floor below is exact
  // (a cast truncates toward zero) and cheap (std::floor is a library call on plain x86-64).
  const double top = road_.lane_count - 1;
  const auto floor_of = [&](double x) {
    x = std::clamp(x, -top - 3.0, top + 3.0);
    const int i = static_cast<int>(x);
    return x < i ? i - 1 : i;
  };
  const int first = -floor_of(-(d_m - half + m) * inverse_lane_width_) - 1;  // ceil(x) - 1
  const int last = floor_of((d_m + half - m) * inverse_lane_width_);
  return {std::clamp(first, 0, road_.lane_count), std::clamp(last, -1, road_.lane_count - 1)};
}

double SafetyMonitor::wrapped_ds(double from_s, double to_s) const {
  return wrap_delta(from_s, to_s, loop_length_m_);
}

const SafetyMonitor::Sample& SafetyMonitor::sample(const Track& t, long back) const {
  const auto n = static_cast<long>(t.ring.size());
  long at = static_cast<long>(ring_head_) - std::clamp(back, 0L, n - 1);
  if (at < 0) at += n;
  return t.ring[static_cast<std::size_t>(at)];
}

void SafetyMonitor::update_track(Track& t, core::FrenetPoint at, double speed_mps, bool appeared) {
  if (appeared) {
    // A body new on the road (the run's start, a car placed) has been in its lanes "always"
    // and has no history: its past is its present.
    t.ring.assign(static_cast<std::size_t>(window_steps_ + 1), Sample{at, speed_mps});
    t.two_lanes_last = kNotIn;
  }
  t.ring[ring_head_] = {at, speed_mps};
  const auto [first, last] = lane_span(at.d_m);
  if (appeared || first != t.span_lo || last != t.span_hi) {  // else its lanes are as they were
    for (int lane = 0; lane < road_.lane_count; ++lane) {
      const auto l = static_cast<std::size_t>(lane);
      long& since = t.lane_since[l];
      if (lane < first || lane > last) {
        since = kNotIn;
      } else if (appeared) {
        since = kAlways;
      } else if (since == kNotIn) {
        since = step_;
        t.entry_self[l] = {at, speed_mps};
        t.entered_now = entries_now_ = true;
      }
    }
    t.span_lo = first;
    t.span_hi = last;
  }
  if (last > first) t.two_lanes_last = step_;
  t.active = true;
  last_step_ = step_;
}

ContactBody SafetyMonitor::contact_body(const Track& self, const Track& other) const {
  const Sample& me = sample(self, 0);
  const Sample& them = sample(other, 0);
  ContactBody b;
  b.frenet = me.frenet;
  b.speed_mps = me.speed_mps;
  b.in_two_lanes = self.span_hi > self.span_lo;
  const double moved_m = me.frenet.d_m - sample(self, window_steps_).frenet.d_m;
  b.toward_other_m = them.frenet.d_m >= me.frenet.d_m ? moved_m : -moved_m;
  return b;
}

LaneEntry SafetyMonitor::lane_entry(const Track& mover, const Track& other,
                                    bool mover_is_ego) const {
  LaneEntry e;
  const auto lane = static_cast<std::size_t>(core::lane_of(sample(other, 0).frenet.d_m, road_));
  const long since = mover.lane_since[lane];
  if (since == kNotIn || since == kAlways) return e;
  for (std::size_t l = 0; l < static_cast<std::size_t>(road_.lane_count); ++l) {
    if (mover.lane_since[l] != kNotIn && mover.lane_since[l] > since) return e;  // not its newest
  }
  if (mover_is_ego) {
    const auto& cars = mover.entry_cars[lane];
    const auto it =
        std::find_if(cars.begin(), cars.end(), [&](const CarAt& c) { return c.id == other.id; });
    if (it == cars.end()) return e;  // the car came onto the road after the ego's entry
    e.ego = mover.entry_self[lane].frenet;
    e.ego_speed_mps = mover.entry_self[lane].speed_mps;
    e.car = it->at.frenet;
    e.car_speed_mps = it->at.speed_mps;
  } else {
    e.car = mover.entry_self[lane].frenet;
    e.car_speed_mps = mover.entry_self[lane].speed_mps;
    e.ego = mover.entry_ego[lane].frenet;
    e.ego_speed_mps = mover.entry_ego[lane].speed_mps;
  }
  const long ended = std::max(since, mover.two_lanes_last);
  e.s_ago = static_cast<double>(last_step_ - ended) * step_s_;
  e.entered_s_ago = static_cast<double>(last_step_ - since) * step_s_;
  return e;
}

void SafetyMonitor::note_entries() {
  if (!entries_now_) return;
  entries_now_ = false;
  // The ego's entries: every car as it was then. A car's entries: the ego as it was then.
  for (std::size_t l = 0; ego_.entered_now && l < static_cast<std::size_t>(road_.lane_count); ++l) {
    if (ego_.lane_since[l] != step_) continue;
    auto& at = ego_.entry_cars[l];
    at.clear();
    for (const Track& t : cars_) {
      if (t.active) at.push_back({t.id, sample(t, 0)});
    }
  }
  ego_.entered_now = false;
  const Sample& ego_now = sample(ego_, 0);
  for (Track& t : cars_) {
    if (!t.active || !t.entered_now) continue;
    t.entered_now = false;
    for (std::size_t l = 0; l < static_cast<std::size_t>(road_.lane_count); ++l) {
      if (t.lane_since[l] == step_) t.entry_ego[l] = ego_now;
    }
  }
}

bool SafetyMonitor::classify_contact(int car_id) {
  const auto it = std::find_if(cars_.begin(), cars_.end(),
                               [&](const Track& t) { return t.active && t.id == car_id; });
  if (it == cars_.end()) return false;
  ContactSituation s;
  s.ego = contact_body(ego_, *it);
  s.car = contact_body(*it, ego_);
  s.ego_entry = lane_entry(ego_, *it, true);
  s.car_entry = lane_entry(*it, ego_, false);
  s.ego_deceleration_mps2 = (sample(ego_, window_steps_).speed_mps - sample(ego_, 0).speed_mps) /
                            (static_cast<double>(window_steps_) * step_s_);
  s.loop_length_m = loop_length_m_;
  s.size = size_;
  contact_class_ = classify_collision(s, p_);
  return true;
}

std::optional<ContactStep> SafetyMonitor::observe(const SafetyEgo& ego,
                                                  std::span<const TrafficCar> cars,
                                                  std::optional<int> contact_id) {
  // Contacts end once the two have been apart for the gap; a touch before then belongs to the
  // contact that car already has with the ego.
  std::erase_if(open_contacts_,
                [&](const OpenContact& c) { return step_ - c.last_step > contact_gap_steps_; });
  const auto open_with = [&](int car_id) {
    return std::find_if(open_contacts_.begin(), open_contacts_.end(),
                        [&](const OpenContact& c) { return c.car_id == car_id; });
  };
  const bool begins = contact_id && open_with(*contact_id) == open_contacts_.end();
  // A contact that begins now is classified from the state of the step before (the tracks
  // still hold it: the two did not touch then); at the first step, from the state now.
  bool classified = false;
  if (begins && step_ > 0) classified = classify_contact(*contact_id);

  // Then the tracks move on to this step.
  if (step_ > 0) ring_head_ = (ring_head_ + 1) % static_cast<std::size_t>(window_steps_ + 1);
  update_track(ego_, ego.frenet, ego.speed_mps, step_ == 0);
  if (cars_.size() != cars.size()) cars_.resize(cars.size());
  for (std::size_t i = 0; i < cars.size(); ++i) {
    const TrafficCar& c = cars[i];
    Track& t = cars_[i];
    if (c.parked) {
      t.active = false;
      continue;
    }
    const bool appeared =
        !t.active || t.id != c.id || step_ == 0 ||
        std::abs(wrapped_ds(sample(t, 1).frenet.s_m, c.map_frenet.s_m)) > kTeleportM;
    t.id = c.id;
    update_track(t, c.map_frenet, c.speed_mps, appeared);
  }
  note_entries();
  if (begins && !classified && !classify_contact(*contact_id)) {
    // A car that is not on the road: the ego could do nothing about it.
    contact_class_ = {CollisionKind::car_cut_in, false};
  }
  std::optional<ContactStep> touch;
  if (begins) {
    open_contacts_.push_back({*contact_id, step_, contact_class_, contacts_begun_++});
    touch = ContactStep{contact_class_, open_contacts_.back().index, true};
  } else if (contact_id) {
    const auto it = open_with(*contact_id);
    it->last_step = step_;
    contact_class_ = it->collision;
    touch = ContactStep{it->collision, it->index, false};
  }
  contact_id_ = contact_id;

  measure();
  const double ttc = std::min(current_.ttc_ahead_s, current_.ttc_entering_s);
  summary_.min_ttc_ahead_s = std::min(summary_.min_ttc_ahead_s, current_.ttc_ahead_s);
  summary_.min_ttc_entering_s = std::min(summary_.min_ttc_entering_s, current_.ttc_entering_s);
  summary_.min_headway_s = std::min(summary_.min_headway_s, current_.headway_s);
  const bool below = ttc < p_.ttc_threshold_s;
  if (step_ > 0) {  // step 0 is the start, before any time has passed
    if (below) summary_.ttc_below_s += step_s_;
    if (current_.headway_s < p_.headway_threshold_s) summary_.headway_below_s += step_s_;
  }
  count_episode(below, contact_id.has_value());
  ++step_;
  return touch;
}

void SafetyMonitor::measure() {
  current_ = {};
  const Sample& me = sample(ego_, 0);
  // The lanes the ego's body is in, and the one it is entering: while it is in two, the one
  // it moves toward (the one it entered last when it does not move across).
  int lowest = ego_.span_lo, highest = ego_.span_hi;
  if (lowest > highest) lowest = highest = core::lane_of(me.frenet.d_m, road_);  // off the road
  int entering = -1;
  if (highest > lowest) {
    const double across_m = me.frenet.d_m - sample(ego_, kDirectionSteps).frenet.d_m;
    const auto since = [&](int lane) { return ego_.lane_since[static_cast<std::size_t>(lane)]; };
    const int last_entered = since(highest) >= since(lowest) ? highest : lowest;
    entering = across_m > kAcrossM ? highest : across_m < -kAcrossM ? lowest : last_entered;
  }

  double lead_gap = kInf, lead_speed = 0.0;                  // the ego's lanes, ahead
  double enter_lead_gap = kInf, enter_lead_speed = 0.0;      // entering lane, ahead
  double enter_follow_gap = kInf, enter_follow_speed = 0.0;  // entering lane, behind
  for (const Track& t : cars_) {
    if (!t.active) continue;
    const Sample& car = sample(t, 0);
    const double ds = wrapped_ds(me.frenet.s_m, car.frenet.s_m);
    const double gap = std::abs(ds) - size_.length_m;
    if (gap < 0.0) continue;  // alongside: neither ahead nor behind
    if (ds > 0.0 && gap < lead_gap && t.span_lo <= highest && t.span_hi >= lowest) {
      lead_gap = gap;
      lead_speed = car.speed_mps;
    }
    if (entering >= 0 && t.span_lo <= entering && entering <= t.span_hi) {
      if (ds > 0.0 && gap < enter_lead_gap) {
        enter_lead_gap = gap;
        enter_lead_speed = car.speed_mps;
      } else if (ds < 0.0 && gap < enter_follow_gap) {
        enter_follow_gap = gap;
        enter_follow_speed = car.speed_mps;
      }
    }
  }
  const double v = me.speed_mps;
  if (lead_gap < kInf) {
    current_.ttc_ahead_s = time_to_collision_s(lead_gap, v, lead_speed);
    if (v >= p_.headway_min_speed_mps) current_.headway_s = lead_gap / v;
  }
  if (enter_lead_gap < kInf) {
    current_.ttc_entering_s = time_to_collision_s(enter_lead_gap, v, enter_lead_speed);
  }
  if (enter_follow_gap < kInf) {
    current_.ttc_entering_s = std::min(
        current_.ttc_entering_s, time_to_collision_s(enter_follow_gap, enter_follow_speed, v));
  }
}

void SafetyMonitor::count_episode(bool below, bool contact) {
  const long gap_steps = std::max<long>(1, std::lround(p_.episode_gap_s / step_s_));
  if (below) {
    if (!in_episode_) {
      in_episode_ = true;
      episode_contact_ = false;
    }
    last_below_step_ = step_;
  }
  if (in_episode_ && contact) episode_contact_ = true;
  if (in_episode_ && !below && step_ - last_below_step_ >= gap_steps) {
    if (!episode_contact_) ++summary_.near_miss_episodes;
    in_episode_ = false;
  }
}

SafetySummary SafetyMonitor::summary() const {
  SafetySummary s = summary_;
  if (in_episode_ && !episode_contact_) ++s.near_miss_episodes;  // one still going at the end
  return s;
}

}  // namespace overtake::sim

namespace overtake::sim {

void SafetyMonitor::archive_track(core::StateArchive& ar, Track& t, bool is_ego) {
  const auto archive_sample = [](core::StateArchive& a, Sample& x) {
    a.io(x.frenet, "sample s and d");
    a.io_speed(x.speed_mps, "sample speed");
  };
  ar.io(t.active, "track active");
  ar.io_range(t.id, -1, 65535, "track car");
  const auto lanes = static_cast<std::size_t>(road_.lane_count);
  for (std::size_t l = 0; l < lanes; ++l) ar.io(t.lane_since[l], "lane since");
  ar.io(t.two_lanes_last, "two lanes last");
  ar.io_range(t.span_lo, -64, 64, "lanes from");
  ar.io_range(t.span_hi, -64, 64, "lanes to");
  ar.io(t.entered_now, "entered now");
  for (std::size_t l = 0; l < lanes; ++l) archive_sample(ar, t.entry_self[l]);
  for (std::size_t l = 0; l < lanes; ++l) archive_sample(ar, t.entry_ego[l]);
  for (std::size_t l = 0; l < lanes; ++l) {
    ar.io_vector(t.entry_cars[l], 1U << 16U, "cars at an entry",
                 [&](core::StateArchive& a, CarAt& c) {
                   a.io_range(c.id, -1, 65535, "car at an entry");
                   archive_sample(a, c.at);
                 });
  }
  // The window's ring: empty until the body is first seen, else one sample per step.
  const auto window = static_cast<std::size_t>(window_steps_ + 1);
  const std::size_t n = ar.io_length(t.ring.size(), window, "window");
  ar.require(n == 0 || n == window, "window: another length (the safety params differ)");
  if (ar.loading()) t.ring.assign(n, Sample{});
  // Of a sample older than the step before, only d is ever read again (and the ego's speed):
  // at the window's far end. The rest is not kept, so that a checkpoint stays small.
  std::uint64_t d_bits = 0, v_bits = 0;
  for (std::size_t i = 0; i < n; ++i) {
    Sample& x = t.ring[i];
    const std::size_t back = (ring_head_ + n - i) % n;
    if (back <= 1) {
      archive_sample(ar, x);
      continue;
    }
    ar.io_delta(x.frenet.d_m, d_bits, "window d", core::StateArchive::kMaxMetres);
    if (is_ego) ar.io_delta(x.speed_mps, v_bits, "window speed", core::StateArchive::kMaxSpeed);
    if (ar.loading()) x.frenet.s_m = 0.0;  // never read
  }
}

void SafetyMonitor::forget_counts() {
  summary_ = SafetySummary{};
  in_episode_ = false;
  episode_contact_ = false;
  open_contacts_.clear();
  contacts_begun_ = 0;
  contact_id_.reset();
}

void SafetyMonitor::archive(core::StateArchive& ar) {
  ar.part("safety");
  ar.io(step_, "step");
  ar.io(last_step_, "tracks' step");
  ar.io(entries_now_, "entries now");
  ar.io_range(ring_head_, 0, static_cast<std::size_t>(window_steps_), "ring head");
  archive_track(ar, ego_, true);
  ar.io_vector(cars_, 1U << 16U, "car tracks",
               [this](core::StateArchive& a, Track& t) { archive_track(a, t, false); });
  ar.io_optional(contact_id_, "contact",
                 [](core::StateArchive& a, int& id) { a.io_range(id, 0, 65535, "contact car"); });
  ar.io_enum(contact_class_.kind, CollisionKind::car_stopped, "contact kind");
  ar.io(contact_class_.at_fault, "contact at fault");
  ar.io(current_.ttc_ahead_s, "ttc ahead");
  ar.io(current_.ttc_entering_s, "ttc entering");
  ar.io(current_.headway_s, "headway");
  ar.io(summary_.min_ttc_ahead_s, "least ttc ahead");
  ar.io(summary_.min_ttc_entering_s, "least ttc entering");
  ar.io(summary_.min_headway_s, "least headway");
  ar.io(summary_.ttc_below_s, "time below ttc");
  ar.io(summary_.headway_below_s, "time below headway");
  ar.io(summary_.near_miss_episodes, "near misses");
  ar.io(in_episode_, "in episode");
  ar.io(episode_contact_, "episode contact");
  ar.io(last_below_step_, "last step below");
}

void SafetyMonitor::archive_contacts(core::StateArchive& ar) {
  ar.part("contacts");
  ar.io_range(contacts_begun_, 0, std::numeric_limits<int>::max(), "contacts begun");
  ar.io_vector(
      open_contacts_, 1U << 16U, "open contacts", [this](core::StateArchive& a, OpenContact& c) {
        a.io_range(c.car_id, 0, 65535, "contact car");
        a.io_range(c.last_step, step_ - contact_gap_steps_ - 1, step_, "contact's last step");
        a.io_enum(c.collision.kind, CollisionKind::car_stopped, "contact kind");
        a.io(c.collision.at_fault, "contact at fault");
        a.io_range(c.index, 0, contacts_begun_ - 1, "contact number");
      });
}

}  // namespace overtake::sim
