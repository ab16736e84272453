#pragma once
// Bringing a planner from outside in step before a cut scenario starts (docs/scenarios.md).
// A planner program, a plugin or a Python planner keeps state overtake cannot see, but that
// state is a function of what it was told. A cut scenario of such a planner's run carries the
// telemetry the planner received over a window before the scenario's start, exactly as it was
// sent, and what it answered. Played to the planner again before the scenario starts (the
// world stays where it is: the answers are compared, never driven), it rebuilds that state;
// once its answers match the recorded ones for `in_step_cycles` cycles in a row, it is in step.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "overtake/core/plan.hpp"
#include "overtake/core/telemetry.hpp"

namespace overtake::sim {

/// The answers in a row that must match for a planner to be in step, by default: about a
/// second of cycles. A planner program's answer carries new points every cycle, computed from
/// its state (its target speed, its lane), so a state that differs shows in the next answers.
inline constexpr int kDefaultInStepCycles = 25;
/// The most cycles a warm-up holds: 6 hours at 50 cycles a second.
inline constexpr std::size_t kMaxWarmUpCycles = std::size_t{1} << 20U;

/// One planner cycle of the recorded run.
struct WarmUpCycle {
  long step = 0;              ///< the world's step when it was told (run time = step × step_s)
  core::Telemetry telemetry;  ///< what the planner was told, as sent (wire-rounded)
  std::vector<core::Vec2> answer;  ///< what it answered, as it answered
  friend bool operator==(const WarmUpCycle&, const WarmUpCycle&) = default;
};

/// The window played before a scenario's start.
struct WarmUp {
  std::vector<WarmUpCycle> cycles;  ///< in order, ending with the cycle before the start
  int in_step_cycles = kDefaultInStepCycles;
  bool from_run_start = false;  ///< the window begins at the run's first cycle (`--warm-up all`)
  friend bool operator==(const WarmUp&, const WarmUp&) = default;
};

/// The cycles as bytes (each double stored exactly, as its bits XOR the same value's one
/// cycle before, so that a general compressor finds the repetition).
[[nodiscard]] std::string encode_warm_up(const WarmUp& warm_up);
/// Reads them back; core::StateError naming `name` and what is wrong.
[[nodiscard]] WarmUp decode_warm_up(std::string_view bytes, std::string_view name);

/// Whether two answers are the same path once the world has read them (the points rounded
/// as the original reads a reply): what decides where the car goes.
[[nodiscard]] bool same_answer(std::span<const core::Vec2> a, std::span<const core::Vec2> b);
/// A digest of an answer as the world reads it (two plays of one window compared cycle by
/// cycle).
[[nodiscard]] std::uint64_t answer_digest(std::span<const core::Vec2> answer);

/// What playing a window did.
struct WarmUpResult {
  std::size_t cycles = 0;  ///< in the window
  std::size_t played = 0;  ///< told (fewer when the planner failed or the run was stopped)
  int in_step_cycles = kDefaultInStepCycles;
  bool from_run_start = false;
  /// The last in_step_cycles answers matched the recorded ones (all of them, when the window is
  /// shorter).
  bool in_step = false;
  /// Cycles played when it came in step for good (the last match of the first run of
  /// in_step_cycles matches that lasted to the end); 0 when not in step.
  std::size_t in_step_after = 0;
  std::size_t matched = 0;            ///< answers that matched the recorded ones
  long first_difference = -1;         ///< the first cycle (from 0) whose answer differed; -1: none
  long last_difference = -1;          ///< the last one
  long first_difference_step = -1;    ///< the world step of first_difference in the recorded run
  double first_difference_t_s = 0.0;  ///< its run time (set by run_drive)
  /// Each played answer's digest (answer_digest), in order: not reported, for comparing plays.
  std::vector<std::uint64_t> digests;
};

/// Tells `planner` every cycle of `warm_up` in order and compares its answers with the
/// recorded ones. Returns before the end when `stop` is set. A planner that throws ends the
/// play: the exception goes up, `result` holding what was played.
void play_warm_up(const WarmUp& warm_up,
                  const std::function<core::PlanResult(const core::Telemetry&)>& planner,
                  const std::atomic<bool>* stop, WarmUpResult& result);

/// The first cycle at which two plays of one window answered differently, or -1 when they
/// agree over the cycles both played.
[[nodiscard]] long first_disagreement(const WarmUpResult& a, const WarmUpResult& b);

}  // namespace overtake::sim
