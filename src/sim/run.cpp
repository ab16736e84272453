#include "overtake/sim/run.hpp"

#include <cmath>
#include <limits>
#include <thread>

#include "overtake/core/cpu_clock.hpp"

namespace overtake::sim {
namespace {

constexpr std::uint64_t kLatencyStream = 20;
constexpr double kProgressEveryS = 10.0;

}  // namespace

// ---- observers ----------------------------------------------------------------------------

ObserverList::ObserverList(std::vector<RunObserver*> observers) {
  for (RunObserver* o : observers) {
    if (o) observers_.push_back(o);
  }
}

void ObserverList::on_frame(const Frame& frame, std::span<const Incident> new_incidents) {
  for (RunObserver* o : observers_) o->on_frame(frame, new_incidents);
}

void ObserverList::on_path(std::span<const core::Vec2> path) {
  for (RunObserver* o : observers_) o->on_path(path);
}

void ObserverList::on_checkpoint(const Checkpoint& checkpoint) {
  for (RunObserver* o : observers_) o->on_checkpoint(checkpoint);
}

RunObserver* ObserverList::get() {
  if (observers_.empty()) return nullptr;
  return observers_.size() == 1 ? observers_.front() : this;
}

// ---- pacing -------------------------------------------------------------------------------

PaceClock::PaceClock(Pace pace, double step_s, Clock::time_point start)
    : pace_(pace),
      period_(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(step_s))),
      start_(start) {}

PaceClock::Clock::time_point PaceClock::due(long step) const {
  if (pace_ == Pace::unpaced) return start_;
  return start_ + step * period_;
}

void PaceClock::wait_for(long step) const {
  if (pace_ == Pace::unpaced) return;
  std::this_thread::sleep_until(due(step));
}

// ---- the stepper --------------------------------------------------------------------------

Stepper::Stepper(World& world, const RunOptions& options)
    : world_(world),
      options_(options),
      total_steps_(world.steps() + std::lround(options.duration_s / world.params().step_s)),
      start_step_(world.steps()),
      scorecard_(world),
      pace_(options.pace, world.params().step_s),
      latency_(core::derive_seed(options.seed, kLatencyStream)),
      next_progress_s_(world.time_s() + kProgressEveryS),
      next_checkpoint_s_(world.time_s()) {
  if (!options.restore.empty()) {
    core::StateArchive ar(options.restore, "checkpoint");
    if (options.reseed) ar.reseed_generators(*options.reseed);
    world_.archive(ar);
    if (options.replayed_traffic) world_.replay_traffic(*options.replayed_traffic);
    if (options.restore_scope == RunOptions::RestoreScope::whole_run) {
      scorecard_.archive(ar);
      archive(ar);
      scorecard_.archive_contacts(ar);
    } else {
      Scorecard skipped(world_);
      skipped.archive(ar);
      archive(ar);
      skipped.archive_contacts(ar);
      scorecard_ = Scorecard(world_);
      scorecard_.continue_rubric(skipped);
      total_steps_ = world_.steps() + std::lround(options.duration_s / world_.params().step_s);
    }
    ar.expect_end();
    start_step_ = world_.steps();
    next_progress_s_ = world_.time_s() + kProgressEveryS;
    next_checkpoint_s_ = world_.time_s();
  }
  emit_frame(0);
}

void Stepper::archive(core::StateArchive& ar) {
  ar.part("stepper");
  ar.io_range(total_steps_, 0, std::lround(kMaxCheckpointRunS / world_.params().step_s),
              "end step");
  ar.io(latency_, "latency stream");
}

std::string Stepper::save() {
  core::StateArchive ar;
  world_.archive(ar);
  scorecard_.archive(ar);
  archive(ar);
  scorecard_.archive_contacts(ar);
  return ar.take();
}

void Stepper::checkpoint_if_due() {
  if (options_.checkpoint_every_s <= 0.0 || !options_.observer) return;
  if (world_.time_s() + 1e-9 < next_checkpoint_s_) return;
  while (next_checkpoint_s_ <= world_.time_s() + 1e-9)
    next_checkpoint_s_ += options_.checkpoint_every_s;
  Checkpoint c;
  c.info.step = world_.steps();
  c.info.t_s = world_.time_s();
  c.run = save();
  if (options_.planner_state) c.planner = options_.planner_state();
  options_.observer->on_checkpoint(c);
}

bool Stepper::finished() const {
  return ended_.has_value() || world_.steps() >= total_steps_;
}

bool Stepper::stop_requested() const {
  return options_.stop != nullptr && options_.stop->load(std::memory_order_relaxed);
}

void Stepper::apply(core::PlanResult plan, std::optional<double> cycle_us, double wall_us) {
  // Whatever the planner (built in, a plugin, Python, a program), a point the world cannot
  // drive to ends the run as the planner's failure, before it reaches the world.
  if (const auto problem = core::path_problem(plan.path)) {
    end(RunEnd::planner_failed, "the planner's path: " + *problem);
    return;
  }
  if (cycle_us) scorecard_.count_cycle(plan, *cycle_us, wall_us);
  if (options_.observer) options_.observer->on_path(plan.path);
  world_.apply_path(std::move(plan.path));
}

void Stepper::count_cycle(const core::PlanResult& plan, double cycle_us, double wall_us) {
  scorecard_.count_cycle(plan, cycle_us, wall_us);
}

void Stepper::step() {
  const std::size_t incidents_before = scorecard_.referee().incidents().size();
  world_.step();
  scorecard_.observe_step(world_);
  pace_.wait_for(world_.steps() - start_step_);
  emit_frame(incidents_before);
  if (options_.progress && world_.time_s() >= next_progress_s_) {  // every 10 simulated s
    options_.progress(world_.time_s(), scorecard_.referee().distance_m());
    next_progress_s_ += kProgressEveryS;
  }
}

void Stepper::step_one_call() {
  const WorldParams& p = world_.params();
  const int k = options_.steps_per_call
                    ? *options_.steps_per_call
                    : latency_.uniform_int(p.min_steps_per_call, p.max_steps_per_call);
  for (int i = 0; i < k && !finished(); ++i) step();
}

PaceClock::Clock::time_point Stepper::next_step_due() const {
  return pace_.due(world_.steps() - start_step_ + 1);
}

void Stepper::end(RunEnd end, std::string reason) {
  if (ended_ || end == RunEnd::completed) return;
  ended_ = RunOutcome{end, world_.time_s(), std::move(reason)};
}

RunReport Stepper::report() const {
  return scorecard_.report(
      world_, ended_.value_or(RunOutcome{RunEnd::completed, world_.time_s(), {}}), options_.clock);
}

void Stepper::emit_frame(std::size_t incidents_before) {
  if (!options_.observer) return;
  scorecard_.fill_frame(world_, frame_);
  const std::vector<Incident>& incidents = scorecard_.referee().incidents();
  options_.observer->on_frame(frame_,
                              std::span<const Incident>(incidents).subspan(incidents_before));
}

// ---- the lock-step loop -------------------------------------------------------------------

RunReport run_drive(World& world, const PlannerFn& planner, const RunOptions& opts) {
  Stepper run(world, opts);
  std::optional<WarmUpResult> warm_up;
  if (opts.warm_up) {
    warm_up.emplace();
    try {
      play_warm_up(*opts.warm_up, planner, opts.stop, *warm_up);
    } catch (const std::exception& e) {
      if (run.stop_requested()) {
        run.end(RunEnd::stopped);
      } else {
        run.end(RunEnd::planner_failed, "in the warm-up, at its cycle " +
                                            std::to_string(warm_up->played + 1) + " of " +
                                            std::to_string(warm_up->cycles) + ": " + e.what());
      }
    }
    if (run.stop_requested()) run.end(RunEnd::stopped);
    warm_up->first_difference_t_s =
        static_cast<double>(warm_up->first_difference_step) * world.params().step_s;
  }
  while (!run.finished()) {
    if (run.stop_requested()) {
      run.end(RunEnd::stopped);
      break;
    }
    run.checkpoint_if_due();
    const core::Telemetry telemetry = run.telemetry();
    core::PlanResult plan;
    const double c0 = core::thread_cpu_us();
    const auto t0 = std::chrono::steady_clock::now();
    try {
      plan = planner(telemetry);
    } catch (const std::exception& e) {
      // A planner that gave up because the user stopped the run has not failed.
      if (run.stop_requested()) {
        run.end(RunEnd::stopped);
      } else {
        run.end(RunEnd::planner_failed, e.what());
      }
      break;
    }
    const double wall =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    const double cycle = opts.clock == CycleClock::thread_cpu ? core::thread_cpu_us() - c0 : wall;
    run.apply(std::move(plan), cycle, wall);
    run.step_one_call();
  }
  RunReport report = run.report();
  report.warm_up = std::move(warm_up);
  return report;
}

}  // namespace overtake::sim
