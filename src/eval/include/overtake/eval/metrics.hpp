#pragma once
// The figures a bench compares planners by, each a small unit with a name, a unit and a
// direction, computed over runs as a ratio of sums (mean speed: miles over hours; a rate:
// 100 x events over miles), and the run rows they are read from.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/core/plan.hpp"
#include "overtake/sim/referee.hpp"
#include "overtake/sim/safety.hpp"

namespace overtake::eval {

/// One run of a bench as the evaluation reads it from its row of runs.jsonl (the report of
/// `drive --json`, with its config).
struct RunRow {
  std::size_t index = 0;  ///< its place in the sweep (0 when the row has none)
  std::string policy;
  std::string traffic;
  std::uint64_t seed = 0;
  std::string map_hash;
  double miles = 0.0;
  double seconds = 0.0;
  double best_incident_free_miles = 0.0;
  std::array<double, sim::kIncidentTypeCount> incidents_by_type{};
  double incidents = 0.0;  ///< of every type
  /// False for rows written before collisions were counted as contacts (they counted one
  /// collision per second of contact): no collision figures then.
  bool contacts_known = false;
  double collisions = 0.0;  ///< contacts
  double at_fault_collisions = 0.0;
  std::array<double, sim::kCollisionKindCount> collisions_by_kind{};
  /// False for rows written before near misses were measured.
  bool has_safety = false;
  double min_ttc_ahead_s = 0.0;  ///< infinity when never measured
  double min_ttc_entering_s = 0.0;
  double min_headway_s = 0.0;
  double ttc_below_s = 0.0;
  double headway_below_s = 0.0;
  double near_misses = 0.0;
  double ttc_threshold_s = 0.0;
  double headway_threshold_s = 0.0;
  // comfort and the planner
  double peak_acceleration_mps2 = 0.0;
  double peak_jerk_mps3 = 0.0;
  double peak_strict_acceleration_mps2 = 0.0;
  double peak_strict_jerk_mps3 = 0.0;
  double planner_p50_us = 0.0;
  double planner_p99_us = 0.0;
  double planner_wall_p99_us = 0.0;
  double planner_cycles = 0.0;
  /// Cycles by plan status (indexed by core::PlanStatus), of the cycles whose status is known.
  std::array<double, core::kPlanStatusCount> plan_status_cycles{};
  /// False for a row whose plan_status is null: its planner does not say how it planned (a
  /// program over the protocol), so its statuses are unknown, not normal.
  bool plan_status_known = true;
  /// Cycles whose status is unknown: all of them when plan_status is null, else those the row
  /// counts as `unknown` (none but in a run that mixes both).
  double plan_status_unknown_cycles = 0.0;
  /// Lane changes the planner's decision layer chose and its path layer did not take, for
  /// their cost and for safety (plan_status.lane_changes_declined); nullopt when the row does
  /// not say (a planner over the protocol, or a row written before they were counted).
  std::optional<std::array<double, 2>> changes_declined;
  bool ended_early = false;
};

/// Reads a row. Throws std::invalid_argument naming `where` (e.g. "results/runs.jsonl, run
/// 3") and the key that is missing or of the wrong type.
[[nodiscard]] RunRow read_run_row(const nlohmann::json& row, std::string_view where);

/// The figures runs are compared by.
enum class Metric : std::uint8_t {
  mean_speed_mph,
  incidents_per_100mi,
  collisions_per_100mi,
  at_fault_collisions_per_100mi,
  near_misses_per_100mi,
};
inline constexpr std::size_t kMetricCount = 5;

/// What a metric is.
struct MetricInfo {
  std::string_view name;   ///< the JSON and CSV key, e.g. "mean_speed_mph"
  std::string_view label;  ///< for tables, e.g. "mean speed"
  std::string_view unit;   ///< e.g. "mph", "/100 mi"
  bool higher_is_better = false;
};

[[nodiscard]] const MetricInfo& info(Metric m);
/// Every metric, in order.
[[nodiscard]] const std::array<Metric, kMetricCount>& all_metrics();
/// The metric of that name, if any.
[[nodiscard]] std::optional<Metric> parse_metric(std::string_view name);

/// A run's share of a metric: the metric over runs is sum(numerator) / sum(denominator).
struct MetricTerms {
  double numerator = 0.0;
  double denominator = 0.0;
};
[[nodiscard]] MetricTerms terms(Metric m, const RunRow& run);
/// True when every run has what the metric needs (rows written before collisions were
/// counted as contacts have no collision figures; before near misses, none of those).
[[nodiscard]] bool available(Metric m, const std::vector<const RunRow*>& runs);
/// Why a metric is not available for some run ("" when it is).
[[nodiscard]] std::string unavailable_reason(Metric m, const std::vector<const RunRow*>& runs);
/// The metric over runs (0 with no exposure).
[[nodiscard]] double value(Metric m, const std::vector<const RunRow*>& runs);
/// The metric of one run.
[[nodiscard]] double value(Metric m, const RunRow& run);

}  // namespace overtake::eval
