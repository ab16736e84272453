#pragma once
// A run's report as JSON (the interface users script against; keys as in simulator.md) and
// as a human scorecard.

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "overtake/sim/run.hpp"

namespace overtake::run {

/// What was run, for the report's `config` key.
struct RunProvenance {
  std::uint64_t seed = 1;
  std::string policy;
  std::string traffic;
  std::string map_path;
  std::string map_hash;
  std::string params_hash;
  int steps_per_call = 0;  ///< 0: drawn per call from the configured range
  int min_steps_per_call = 1;
  int max_steps_per_call = 3;
  double minutes = 0.0;
  std::string scenario;  ///< the scenario's name (or file) when scripted; empty otherwise
  /// `sim --planner`: the remote planner's address (`policy` is then its --name, or this
  /// address); empty for a planner in this process. Shown on the scorecard only.
  std::string planner_url;
  /// A planner brought by a flag (plugin, Python, program): what it is, as a JSON object's
  /// text (`PlannerEntry::describe`); empty for a built-in policy. In the report's
  /// config.planner.
  std::string planner;
  /// A planner program's output (`--planner-cmd`): the log file; empty otherwise.
  std::string planner_log;
};

/// One incident as the report lists it: type, t_s, s_m, lane, value (in `unit`), unit.
[[nodiscard]] nlohmann::json incident_to_json(const sim::Incident& incident);

/// How every table and message names a collision's class: its kind and whose fault it was,
/// e.g. "hit_from_behind (not at fault)".
[[nodiscard]] std::string collision_text(const sim::CollisionClass& collision);

/// A contact (a collision as evaluation counts it) as the collision incident at its first step,
/// numbered `index`: what a failure is named and cut by.
[[nodiscard]] sim::Incident contact_incident(const sim::Contact& contact, int index);

/// How long after a run's start a path that leaves the road points at a planner driving
/// another map (s).
inline constexpr double kMapHintWithinS = 10.0;

/// The hint for the commonest mistake with a planner program: it reads its own map file, and
/// benched on another map its path leaves the road from its first seconds. Non-empty when a
/// planner from outside (p.planner or p.planner_url set) booked an outside-lane incident within
/// kMapHintWithinS of the run's start.
[[nodiscard]] std::string map_hint(const sim::RunReport& r, const RunProvenance& p);

/// The warm-up as the report's `warm_up` key.
[[nodiscard]] nlohmann::json warm_up_to_json(const sim::WarmUpResult& w);
/// The warm-up in one line: "1461 cycles told before the start, in step after 25" or "NOT IN
/// STEP ...".
[[nodiscard]] std::string warm_up_text(const sim::WarmUpResult& w);

/// The JSON report. Deterministic for a given run apart from the `timing` key.
[[nodiscard]] nlohmann::json report_to_json(const sim::RunReport& r, const RunProvenance& p);

/// A human-readable scorecard (several lines, ending with a newline).
[[nodiscard]] std::string format_scorecard(const sim::RunReport& r, const RunProvenance& p);

}  // namespace overtake::run
