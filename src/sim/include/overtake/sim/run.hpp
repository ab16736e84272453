#pragma once
// Running a world with a planner. One stepper (Stepper) owns a run's course: the world's
// steps, the scorecard, the watchers, the pacing clock, the latency draw and how the run
// ends. Two loops drive it: run_drive here, lock-step (telemetry, plan, K steps; an
// in-process policy or a remote planner one round trip at a time), and the protocol's real
// time loop, which steps on the wall clock while the planner thinks.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "overtake/core/plan.hpp"
#include "overtake/core/random.hpp"
#include "overtake/core/telemetry.hpp"
#include "overtake/sim/checkpoint.hpp"
#include "overtake/sim/frame.hpp"
#include "overtake/sim/recorded_traffic.hpp"
#include "overtake/sim/scorecard.hpp"
#include "overtake/sim/warm_up.hpp"
#include "overtake/sim/world.hpp"

namespace overtake::sim {

/// A planner as the loop sees it: telemetry in, plan out. It may throw PlannerFailure (or
/// any std::exception) to end the run (e.g. a remote planner that stalled); the report so
/// far is kept.
using PlannerFn = std::function<core::PlanResult(const core::Telemetry&)>;

/// Raised by a PlannerFn that cannot go on.
struct PlannerFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Watches a run as it goes (a replay recording, a live view). Called on the loop's thread;
/// a run without a watcher builds no frames.
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  /// The state before the first step (step 0), then after every step, with the incidents
  /// the referee counted in that step.
  virtual void on_frame(const Frame& frame, std::span<const Incident> new_incidents) = 0;
  /// A path the planner sent, as sent (before the wire rounding and the trim). Lock-step: it
  /// was planned from the state of the last frame; real time: it arrived then.
  virtual void on_path(std::span<const core::Vec2> path) = 0;
  /// A checkpoint of the run at the start of a planner cycle (RunOptions::checkpoint_every_s);
  /// its info holds the step and time only (the watcher knows what was run).
  virtual void on_checkpoint(const Checkpoint& /*checkpoint*/) {}
};

/// Passes every call on to several observers, in the order given (null ones are skipped).
class ObserverList final : public RunObserver {
 public:
  explicit ObserverList(std::vector<RunObserver*> observers);
  void on_frame(const Frame& frame, std::span<const Incident> new_incidents) override;
  void on_path(std::span<const core::Vec2> path) override;
  void on_checkpoint(const Checkpoint& checkpoint) override;
  /// The single observer when there is one, this list when there are more, else null.
  [[nodiscard]] RunObserver* get();

 private:
  std::vector<RunObserver*> observers_;
};

/// How fast simulated time goes.
enum class Pace : std::uint8_t {
  unpaced,    ///< as fast as the machine goes
  real_time,  ///< step k no earlier than k step times of wall time after the start
};

/// The wall-clock times at which steps fall due under a pace.
class PaceClock {
 public:
  using Clock = std::chrono::steady_clock;
  PaceClock(Pace pace, double step_s, Clock::time_point start = Clock::now());
  /// When step `step` (counted from the start) falls due; the start itself when unpaced.
  [[nodiscard]] Clock::time_point due(long step) const;
  /// Waits until step `step` is due (returns at once when unpaced).
  void wait_for(long step) const;
  [[nodiscard]] Pace pace() const { return pace_; }

 private:
  Pace pace_;
  Clock::duration period_;
  Clock::time_point start_;
};

/// How long and how to run.
struct RunOptions {
  double duration_s = 1800.0;
  /// Steps the world advances after each reply; unset: drawn from the params' range by seed.
  std::optional<int> steps_per_call;
  std::uint64_t seed = 1;  ///< for the latency draw
  /// Called now and then with the simulated time (for progress displays).
  std::function<void(double t_s, double distance_m)> progress;
  /// When set (and true), the run stops at the next step or cycle, ended as stopped.
  const std::atomic<bool>* stop = nullptr;
  /// When set, sees every frame and every path (see RunObserver); not owned.
  RunObserver* observer = nullptr;
  /// The pacing clock (real time for a live view, and for the protocol's real-time loop).
  Pace pace = Pace::unpaced;
  /// What a cycle's planner time measures: an in-process planner's thread CPU time, or the
  /// round trip to a remote planner.
  CycleClock clock = CycleClock::thread_cpu;
  /// When not empty: the run's state (Checkpoint::run) to restore before the first frame, so
  /// that the run goes on from where the checkpoint was taken (the duration and the latency
  /// draw are the checkpoint's, not the options').
  std::string_view restore;
  /// What of `restore` is taken: the whole run (it goes on as if it had never stopped), or
  /// the world and the latency draw only (a cut scenario: the scorecard counts afresh, its
  /// referee, safety monitor and lane tracker going on from the run's so that the rubric counts
  /// at the same steps and contacts are classified alike, and the run lasts `duration_s` from
  /// the checkpoint's time).
  enum class RestoreScope : std::uint8_t {
    whole_run,
    world
  } restore_scope = RestoreScope::whole_run;
  /// When set (with `restore`): every random generator of the restored state (traffic's
  /// placement and wander streams, the latency draw) starts afresh from this seed, the values
  /// already drawn kept (a branch of the run: the same world, new random draws from the same
  /// distributions; docs/evaluation.md, "Rare events").
  std::optional<std::uint64_t> reseed;
  /// When set (with `restore`): once the world is restored, its cars follow these recorded
  /// bodies (a cut scenario's replayed traffic; not owned).
  const RecordedTraffic* replayed_traffic = nullptr;
  /// Every this many simulated seconds, at the start of a planner cycle (the first included),
  /// the watcher gets a checkpoint (0: never).
  double checkpoint_every_s = 0.0;
  /// The planner's state for those checkpoints; unset: the planner keeps none overtake sees.
  std::function<std::string()> planner_state;
  /// When set (a cut scenario driven by a planner from outside): run_drive first plays this
  /// window to the planner (play_warm_up; the world does not move), and the report says how
  /// it went (RunReport::warm_up). Not owned.
  const WarmUp* warm_up = nullptr;
};

/// The course of one run. Made before the first step (the watcher sees the first frame
/// then); the loop asks it for telemetry, hands it the planner's plans, steps it, and ends it.
class Stepper {
 public:
  /// The world must outlive the stepper. With RunOptions::restore, the world's state, the
  /// scorecard's and the stepper's own are restored from it (core::StateError when the bytes
  /// do not fit this world).
  Stepper(World& world, const RunOptions& options);

  /// The run's state now (Checkpoint::run): the world, the scorecard and the stepper.
  [[nodiscard]] std::string save();
  /// At the start of a planner cycle: gives the watcher a checkpoint when one is due.
  void checkpoint_if_due();
  /// The step at which the run has gone its duration.
  [[nodiscard]] long end_step() const { return total_steps_; }

  /// True once the run has gone its duration or has been ended.
  [[nodiscard]] bool finished() const;
  /// True when the user asked the run to stop (RunOptions::stop).
  [[nodiscard]] bool stop_requested() const;
  /// What the planner is told now.
  [[nodiscard]] core::Telemetry telemetry() const { return world_.telemetry(); }
  /// A plan for the world to drive: the watcher sees its path, the world takes it, and
  /// (for a planner cycle: with `cycle_us` and `wall_us`) the scorecard counts its status and
  /// time.
  void apply(core::PlanResult plan, std::optional<double> cycle_us = std::nullopt,
             double wall_us = 0.0);
  /// Counts a planner cycle that brought no new path (a remote planner's `manual` reply to
  /// a full telemetry: the world keeps its queue).
  void count_cycle(const core::PlanResult& plan, double cycle_us, double wall_us);
  /// One world step now (the scorecard, the watcher, the progress display see it).
  void step();
  /// Steps until the next planner call in lock-step: K steps, K drawn from the latency range
  /// by the seed (or fixed by the options), each when the pace lets it fall due; fewer when
  /// the run finishes.
  void step_one_call();
  /// When the next step falls due on the pacing clock.
  [[nodiscard]] PaceClock::Clock::time_point next_step_due() const;
  /// Ends the run early. The first end counts; a run that went its duration has completed.
  void end(RunEnd end, std::string reason = {});
  /// The report (the run completed unless it was ended).
  [[nodiscard]] RunReport report() const;

  [[nodiscard]] World& world() { return world_; }
  [[nodiscard]] const Scorecard& scorecard() const { return scorecard_; }

 private:
  void emit_frame(std::size_t incidents_before);
  void archive(core::StateArchive& ar);

  World& world_;
  RunOptions options_;
  long total_steps_;
  long start_step_;
  Scorecard scorecard_;
  PaceClock pace_;
  core::Rng latency_;
  std::optional<RunOutcome> ended_;
  double next_progress_s_;
  double next_checkpoint_s_ = 0.0;
  Frame frame_;  // scratch for the watcher
};

/// The lock-step loop: telemetry -> planner -> path -> K steps, until the duration is
/// reached (after RunOptions::warm_up, when set: a planner that fails in it ends the run at its
/// start), the planner fails (the run ends as planner_failed, or as stopped when the stop
/// flag was set meanwhile) or the user stops it. Returns the report (also on failure).
[[nodiscard]] RunReport run_drive(World& world, const PlannerFn& planner, const RunOptions& opts);

}  // namespace overtake::sim
