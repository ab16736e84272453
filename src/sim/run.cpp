#include "overtake/sim/run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "overtake/core/cpu_clock.hpp"
#include "overtake/core/random.hpp"

namespace overtake::sim {
namespace {

constexpr std::uint64_t kLatencyStream = 20;
constexpr double kProgressEveryS = 10.0;

}  // namespace

LaneTracker::LaneTracker(const core::RoadParams& road, double settle_m)
    : road_(road), settle_m_(settle_m), time_in_lane_s_(static_cast<std::size_t>(road.lane_count), 0.0) {}

void LaneTracker::observe(double d_m, double dt_s) {
  const int lane = core::lane_of(d_m, road_);
  time_in_lane_s_[static_cast<std::size_t>(lane)] += dt_s;
  if (std::abs(d_m - core::lane_center_d(lane, road_)) > settle_m_) return;
  if (settled_ >= 0 && settled_ != lane) ++changes_;
  settled_ = lane;
}

ObserverList::ObserverList(std::vector<RunObserver*> observers) {
  for (RunObserver* o : observers) {
    if (o) observers_.push_back(o);
  }
}

void ObserverList::on_state(const World& world) {
  for (RunObserver* o : observers_) o->on_state(world);
}

void ObserverList::on_path(const World& world, std::span<const core::Vec2> path) {
  for (RunObserver* o : observers_) o->on_path(world, path);
}

RunObserver* ObserverList::get() {
  if (observers_.empty()) return nullptr;
  return observers_.size() == 1 ? observers_.front() : this;
}

RunReport run_drive(World& world, const PlannerFn& planner, const RunOptions& opts) {
  const WorldParams& p = world.params();
  const long total_steps = std::lround(opts.duration_s / p.step_s);
  core::Rng latency(core::derive_seed(opts.seed, kLatencyStream));
  LaneTracker lanes(p.road);
  // Timing in fixed memory: a 7-day run has 15 million cycles.
  core::QuantileSketch cycle_us;  // thread CPU time (or the round trip of a remote planner)
  core::QuantileSketch wall_us;

  std::string ended_early;
  double next_progress_s = kProgressEveryS;
  RunObserver* const observer = opts.observer;
  if (observer) observer->on_state(world);
  while (world.steps() < total_steps) {
    if (opts.stop && opts.stop->load(std::memory_order_relaxed)) {
      ended_early = "stopped";
      break;
    }
    const core::Telemetry telemetry = world.telemetry();
    std::vector<core::Vec2> path;
    const double c0 = core::thread_cpu_us();
    const auto t0 = std::chrono::steady_clock::now();
    try {
      path = planner(telemetry).path;
    } catch (const std::exception& e) {
      ended_early = std::string("planner failed at t = ") +
                           std::to_string(world.time_s()) + " s: " + e.what();
      break;
    }
    const auto t1 = std::chrono::steady_clock::now();
    const double wall = std::chrono::duration<double, std::micro>(t1 - t0).count();
    cycle_us.add(opts.remote_planner ? wall : core::thread_cpu_us() - c0);
    wall_us.add(wall);
    if (observer) observer->on_path(world, path);
    world.apply_path(std::move(path));

    const int k = opts.steps_per_call
                      ? *opts.steps_per_call
                      : latency.uniform_int(p.min_steps_per_call, p.max_steps_per_call);
    for (int i = 0; i < k && world.steps() < total_steps; ++i) {
      world.step();
      lanes.observe(world.ego().frenet.d_m, p.step_s);
      if (observer) observer->on_state(world);
    }
    if (opts.progress && world.time_s() >= next_progress_s) {  // every 10 simulated seconds
      opts.progress(world.time_s(), world.referee().distance_m());
      next_progress_s += kProgressEveryS;
    }
  }

  RunReport report = summarize(world, lanes, cycle_us, std::move(ended_early),
                               opts.remote_planner ? "round_trip" : "thread_cpu");
  report.timing.wall_p99_us = wall_us.quantile(0.99);
  report.timing.wall_max_us = wall_us.max();
  return report;
}

RunReport summarize(const World& world, const LaneTracker& lanes, const core::QuantileSketch& cycle_us,
                    std::string ended_early, std::string clock) {
  RunReport report;
  report.ended_early = std::move(ended_early);
  const Referee& ref = world.referee();
  report.duration_s = world.time_s();
  report.distance_m = ref.distance_m();
  report.mean_speed_mps = report.duration_s > 0.0 ? report.distance_m / report.duration_s : 0.0;
  report.best_incident_free_m = ref.best_incident_free_m();
  report.incidents = ref.incidents();
  report.incident_counts = ref.counts();
  report.exact_outside_lane = ref.exact_outside_lane_count();
  report.peak = ref.peaks();
  report.lane_changes = lanes.lane_changes();
  report.time_in_lane_s = lanes.time_in_lane_s();
  report.planner_cycles = static_cast<long>(cycle_us.count());
  report.timing.p50_us = cycle_us.quantile(0.5);
  report.timing.p99_us = cycle_us.quantile(0.99);
  report.timing.max_us = cycle_us.max();
  report.timing.cycles = static_cast<long>(cycle_us.count());
  report.timing.clock = std::move(clock);
  report.timing.wall_p99_us = report.timing.p99_us;
  report.timing.wall_max_us = report.timing.max_us;
  return report;
}

}  // namespace overtake::sim
