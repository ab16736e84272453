#include "overtake/sim/scorecard.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "overtake/sim/world.hpp"

namespace overtake::sim {

std::string_view to_string(RunEnd end) {
  switch (end) {
    case RunEnd::completed:
      return "completed";
    case RunEnd::stopped:
      return "stopped";
    case RunEnd::planner_failed:
      return "planner_failed";
  }
  return "unknown";
}

std::string ended_early_text(const RunOutcome& outcome) {
  switch (outcome.end) {
    case RunEnd::completed:
      return {};
    case RunEnd::stopped:
      return "stopped";
    case RunEnd::planner_failed:
      return "planner failed at t = " + std::to_string(outcome.t_s) + " s: " + outcome.reason;
  }
  return {};
}

std::string_view to_string(CycleClock clock) {
  return clock == CycleClock::thread_cpu ? "thread_cpu" : "round_trip";
}

LaneTracker::LaneTracker(const core::RoadParams& road, double settle_m)
    : road_(road),
      settle_m_(settle_m),
      time_in_lane_s_(static_cast<std::size_t>(road.lane_count), 0.0) {}

void LaneTracker::observe(double d_m, double dt_s) {
  const int lane = core::lane_of(d_m, road_);
  time_in_lane_s_[static_cast<std::size_t>(lane)] += dt_s;
  if (std::abs(d_m - core::lane_center_d(lane, road_)) > settle_m_) return;
  if (settled_ >= 0 && settled_ != lane) ++changes_;
  settled_ = lane;
}

void Scorecard::continue_rubric(const Scorecard& run) {
  referee_ = run.referee_;
  referee_.forget_counts();
  safety_ = run.safety_;
  safety_.forget_counts();
  lanes_ = run.lanes_;
  lanes_.forget_counts();
}

void LaneTracker::forget_counts() {
  changes_ = 0;
  std::fill(time_in_lane_s_.begin(), time_in_lane_s_.end(), 0.0);
}

Scorecard::Scorecard(const World& world)
    : referee_(world.params().referee, world.params().step_s, world.params().road),
      safety_(world.params().safety, world.params().step_s, world.params().road, world.params().car,
              world.chords().loop_length_m()),
      lanes_(world.params().road),
      step_s_(world.params().step_s),
      start_s_(world.time_s()) {
  // The safety monitor's first look: the start, before any step.
  (void)safety_.observe({world.ego().map_frenet, world.ego().speed_mps}, world.traffic().cars(),
                        std::nullopt);
  // The rubric's first block compares against the speed before the first step (at rest,
  // unless a scenario starts the ego moving).
  referee_.set_initial_speed(world.ego().speed_mps);
}

namespace {
constexpr auto kCollision = static_cast<std::size_t>(IncidentType::collision);
}  // namespace

void Scorecard::observe_step(const World& world) {
  EgoFrame frame = world.ego_frame();
  const std::optional<ContactStep> touch = safety_.observe(
      {world.ego().map_frenet, world.ego().speed_mps}, world.traffic().cars(), frame.collided_with);
  Contact* contact = nullptr;
  if (touch) {
    frame.collision = touch->collision;
    frame.contact = touch->index;
    if (touch->begins) {
      contacts_.push_back({*frame.collided_with, frame.t_s, frame.t_s, frame.s_m,
                           core::lane_of(frame.d_m, world.params().road), touch->collision, 0});
    }
    contact = &contacts_[static_cast<std::size_t>(touch->index)];
    contact->end_t_s = frame.t_s;
  }
  const int collisions_before = referee_.counts()[kCollision];
  referee_.observe(frame);
  if (contact && referee_.counts()[kCollision] > collisions_before) ++contact->rubric_collisions;
  lanes_.observe(world.ego().frenet.d_m, step_s_);
}

void Scorecard::count_cycle(const core::PlanResult& plan, double cycle_us, double wall_us) {
  cycle_us_.add(cycle_us);
  wall_us_.add(wall_us);
  if (!plan.status_known) {
    ++unknown_status_cycles_;
    return;
  }
  ++status_cycles_[static_cast<std::size_t>(plan.status)];
  if (plan.change_declined == core::ChangeDeclined::for_cost) ++declined_for_cost_;
  if (plan.change_declined == core::ChangeDeclined::for_safety) ++declined_for_safety_;
  if (plan.status != core::PlanStatus::normal && first_reason_.empty()) {
    first_reason_ = plan.reason.empty() ? std::string(core::to_string(plan.status)) : plan.reason;
  }
}

void Scorecard::fill_frame(const World& world, Frame& f) const {
  const EgoState& ego = world.ego();
  f.step = world.steps();
  f.position = ego.position;
  f.yaw_rad = ego.yaw_rad;
  f.speed_mps = ego.speed_mps;
  f.s_m = ego.frenet.s_m;
  f.d_m = ego.frenet.d_m;
  f.strict = referee_.current_strict();
  f.safety = safety_.current();
  f.distance_m = referee_.distance_m();
  f.incident_free_m = referee_.incident_free_m();
  f.best_incident_free_m = referee_.best_incident_free_m();
  const Traffic& traffic = world.traffic();
  f.cars.resize(traffic.cars().size());
  for (std::size_t i = 0; i < f.cars.size(); ++i) {
    const TrafficCar& c = traffic.cars()[i];
    const core::OrientedBox box = traffic.footprint(c);
    f.cars[i] = {c.id, box.center, box.heading_rad, c.speed_mps};
  }
}

RunReport Scorecard::report(const World& world, RunOutcome outcome, CycleClock clock) const {
  RunReport r;
  r.outcome = std::move(outcome);
  r.duration_s = world.time_s() - start_s_;
  r.distance_m = referee_.distance_m();
  r.mean_speed_mps = r.duration_s > 0.0 ? r.distance_m / r.duration_s : 0.0;
  r.best_incident_free_m = referee_.best_incident_free_m();
  r.incidents = referee_.incidents();
  r.incident_counts = referee_.counts();
  r.contacts = contacts_;
  r.exact_outside_lane = referee_.exact_outside_lane_count();
  r.peak = referee_.peaks();
  r.safety = safety_.summary();
  r.lane_changes = lanes_.lane_changes();
  r.time_in_lane_s = lanes_.time_in_lane_s();
  r.planner_cycles = unknown_status_cycles_;
  for (const long n : status_cycles_) r.planner_cycles += n;
  r.plan_status_cycles = status_cycles_;
  r.first_plan_reason = first_reason_;
  r.plan_status_unknown_cycles = unknown_status_cycles_;
  r.changes_declined_for_cost = declined_for_cost_;
  r.changes_declined_for_safety = declined_for_safety_;
  r.timing.p50_us = cycle_us_.quantile(0.5);
  r.timing.p99_us = cycle_us_.quantile(0.99);
  r.timing.max_us = cycle_us_.max();
  r.timing.cycles = static_cast<long>(cycle_us_.count());
  r.timing.clock = clock;
  r.timing.wall_p99_us = wall_us_.quantile(0.99);
  r.timing.wall_max_us = wall_us_.max();
  return r;
}

}  // namespace overtake::sim

namespace overtake::sim {

void LaneTracker::archive(core::StateArchive& ar) {
  ar.io_range(settled_, -1, road_.lane_count - 1, "settled lane");
  ar.io(changes_, "lane changes");
  const std::size_t n = time_in_lane_s_.size();
  ar.require(ar.io_length(n, n, "time in lane") == n, "time in lane: another number of lanes");
  for (double& t : time_in_lane_s_) ar.io(t, "time in lane");
}

void Scorecard::archive_contacts(core::StateArchive& ar) {
  if (ar.loading() && ar.at_end()) {  // a checkpoint of a build before contacts
    contacts_.clear();
    return;
  }
  safety_.archive_contacts(ar);
  ar.io_vector(contacts_, 1U << 24U, "contacts", [](core::StateArchive& a, Contact& c) {
    a.io_range(c.car_id, 0, 65535, "contact car");
    a.io(c.t_s, "contact start");
    a.io(c.end_t_s, "contact end");
    a.require(c.end_t_s >= c.t_s, "contact end: before its start");
    a.io_metres(c.s_m, "contact s");
    a.io_range(c.lane, -64, 128, "contact lane");
    a.io_enum(c.collision.kind, CollisionKind::car_stopped, "contact kind");
    a.io(c.collision.at_fault, "contact at fault");
    a.io_range(c.rubric_collisions, 0, std::numeric_limits<int>::max(), "contact's incidents");
  });
  ar.require(static_cast<std::size_t>(safety_.contacts_begun()) == contacts_.size(),
             "contacts: another number than the safety monitor began");
  if (ar.loading()) referee_.link_contacts(contacts_);
  // The lane changes declined, after the contacts: a checkpoint of a build before them
  // counts none so far.
  if (ar.loading() && ar.at_end()) {
    declined_for_cost_ = 0;
    declined_for_safety_ = 0;
    return;
  }
  ar.part("lane changes declined");
  constexpr long kMaxCycles = std::numeric_limits<long>::max();
  ar.io_range(declined_for_cost_, 0, kMaxCycles, "lane changes declined for cost");
  ar.io_range(declined_for_safety_, 0, kMaxCycles, "lane changes declined for safety");
}

void Scorecard::archive(core::StateArchive& ar) {
  referee_.archive(ar);
  safety_.archive(ar);
  ar.part("scorecard");
  lanes_.archive(ar);
  ar.io(start_s_, "start time");
  // Cycles of unknown status (a planner over the protocol), when there are some, go before
  // the counts by status as a negative number, -1 - count, where those have a count (never
  // negative): the checkpoints of every other run keep the bytes of the format without them,
  // so that the scenarios cut before still restore.
  constexpr long kMaxCycles = std::numeric_limits<long>::max();
  long first = unknown_status_cycles_ > 0 ? -1 - unknown_status_cycles_ : status_cycles_[0];
  ar.io_range(first, std::numeric_limits<long>::min(), kMaxCycles, "cycles");
  std::size_t next = 0;
  if (first < 0) {
    unknown_status_cycles_ = -1 - first;
  } else {
    unknown_status_cycles_ = 0;
    status_cycles_[0] = first;
    next = 1;
  }
  for (; next < status_cycles_.size(); ++next)
    ar.io_range(status_cycles_[next], 0, kMaxCycles, "cycles");
  ar.io(first_reason_, 4096, "first plan reason");
}

}  // namespace overtake::sim
