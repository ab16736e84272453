#include "overtake/eval/metrics.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace overtake::eval {
namespace {

using nlohmann::json;

constexpr double kInf = std::numeric_limits<double>::infinity();
/// Bounds of what a run can hold (a week at most, far under these): beyond them a row is not
/// a run of this program, and sums of such rows would overflow.
constexpr double kMaxAmount = 1e12;
constexpr double kMaxCount = 1e9;

class RowReader {
 public:
  RowReader(const json& row, std::string_view where) : row_(row), where_(where) {
    if (!row.is_object()) fail("", "is not a JSON object");
  }

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw std::invalid_argument(std::string(where_) + ": " +
                                (key.empty() ? "the row" : "'" + key + "'") + " " + what);
  }

  const json& at(const json& obj, const std::string& key, const std::string& path) const {
    if (!obj.is_object() || !obj.contains(key)) fail(path, "is missing");
    return obj.at(key);
  }

  double number(const json& obj, const std::string& key, const std::string& path) const {
    const json& v = at(obj, key, path);
    if (!v.is_number()) fail(path, "is not a number: " + v.dump());
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail(path, "is not finite");
    return d;
  }
  double number(const std::string& key) const { return number(row_, key, key); }

  /// A number in [0, max]: a distance, a duration, a time below a threshold.
  double amount(const json& obj, const std::string& key, const std::string& path,
                double max = kMaxAmount) const {
    const double d = number(obj, key, path);
    if (d < 0.0 || d > max) {
      fail(path, "is out of range: " + std::to_string(d) + " (0 to " + std::to_string(max) + ")");
    }
    return d;
  }
  double amount(const std::string& key) const { return amount(row_, key, key); }

  /// A count of events: a whole number in [0, kMaxCount].
  double count(const json& obj, const std::string& key, const std::string& path) const {
    const double d = amount(obj, key, path, kMaxCount);
    if (d != std::floor(d)) fail(path, "is not a whole number: " + std::to_string(d));
    return d;
  }

  /// A number, or infinity when null (a figure never measured).
  double number_or_inf(const json& obj, const std::string& key, const std::string& path) const {
    const json& v = at(obj, key, path);
    if (v.is_null()) return kInf;
    return amount(obj, key, path);
  }

  const json& object(const json& obj, const std::string& key, const std::string& path) const {
    const json& v = at(obj, key, path);
    if (!v.is_object()) fail(path, "is not an object");
    return v;
  }

  std::string text(const json& obj, const std::string& key, const std::string& path) const {
    const json& v = at(obj, key, path);
    if (!v.is_string()) fail(path, "is not a string: " + v.dump());
    return v.get<std::string>();
  }

  const json& row() const { return row_; }

 private:
  const json& row_;
  std::string_view where_;
};

constexpr double kSecondsPerHour = 3600.0;

}  // namespace

RunRow read_run_row(const json& row, std::string_view where) {
  const RowReader r(row, where);
  RunRow out;
  if (row.contains("index") && row["index"].is_number_unsigned()) {
    out.index = row["index"].get<std::size_t>();
  }
  const json& config = r.object(row, "config", "config");
  out.policy = r.text(config, "policy", "config.policy");
  out.traffic = r.text(config, "traffic", "config.traffic");
  const json& seed = r.at(config, "seed", "config.seed");
  if (!seed.is_number_unsigned()) r.fail("config.seed", "is not a seed: " + seed.dump());
  out.seed = seed.get<std::uint64_t>();
  if (config.contains("map") && config["map"].is_object() && config["map"].contains("hash") &&
      config["map"]["hash"].is_string()) {
    out.map_hash = config["map"]["hash"].get<std::string>();
  }
  out.miles = r.amount("distance_miles");
  out.seconds = r.amount("duration_s");
  out.best_incident_free_miles = r.amount("best_incident_free_miles");
  const json& counts = r.object(row, "incident_counts", "incident_counts");
  for (std::size_t t = 0; t < sim::kIncidentTypeCount; ++t) {
    const std::string name(sim::to_string(static_cast<sim::IncidentType>(t)));
    out.incidents_by_type[t] = r.count(counts, name, "incident_counts." + name);
    out.incidents += out.incidents_by_type[t];
  }
  // Collisions as contacts: rows that list them (older rows counted a collision for every
  // second of contact, and those counts are not comparable).
  if (row.contains("collisions") && row["collisions"].is_object() &&
      row["collisions"].contains("contacts")) {
    const json& c = r.object(row, "collisions", "collisions");
    out.contacts_known = true;
    out.collisions = r.count(c, "total", "collisions.total");
    out.at_fault_collisions = r.count(c, "at_fault", "collisions.at_fault");
    if (out.at_fault_collisions > out.collisions) {
      r.fail("collisions.at_fault", "is more than collisions.total");
    }
    const json& by_kind = r.object(c, "by_kind", "collisions.by_kind");
    double kinds = 0.0;
    for (std::size_t k = 0; k < sim::kCollisionKindCount; ++k) {
      const std::string name(sim::to_string(static_cast<sim::CollisionKind>(k)));
      out.collisions_by_kind[k] = r.count(by_kind, name, "collisions.by_kind." + name);
      kinds += out.collisions_by_kind[k];
    }
    if (kinds != out.collisions) r.fail("collisions.by_kind", "does not add up to total");
  }
  if (row.contains("safety")) {
    const json& s = r.object(row, "safety", "safety");
    out.has_safety = true;
    out.min_ttc_ahead_s = r.number_or_inf(s, "min_ttc_ahead_s", "safety.min_ttc_ahead_s");
    out.min_ttc_entering_s = r.number_or_inf(s, "min_ttc_entering_s", "safety.min_ttc_entering_s");
    out.min_headway_s = r.number_or_inf(s, "min_time_headway_s", "safety.min_time_headway_s");
    out.ttc_below_s = r.amount(s, "time_ttc_below_s", "safety.time_ttc_below_s");
    out.headway_below_s = r.amount(s, "time_headway_below_s", "safety.time_headway_below_s");
    out.near_misses = r.count(s, "near_miss_episodes", "safety.near_miss_episodes");
    out.ttc_threshold_s = r.amount(s, "ttc_threshold_s", "safety.ttc_threshold_s");
    out.headway_threshold_s = r.amount(s, "headway_threshold_s", "safety.headway_threshold_s");
  }
  const json& peak = r.object(row, "peak", "peak");
  out.peak_acceleration_mps2 = r.number(peak, "acceleration_mps2", "peak.acceleration_mps2");
  out.peak_jerk_mps3 = r.number(peak, "jerk_mps3", "peak.jerk_mps3");
  out.peak_strict_acceleration_mps2 =
      r.number(peak, "strict_acceleration_mps2", "peak.strict_acceleration_mps2");
  out.peak_strict_jerk_mps3 = r.number(peak, "strict_jerk_mps3", "peak.strict_jerk_mps3");
  const json& timing = r.object(row, "timing", "timing");
  out.planner_p50_us = r.number(timing, "p50_us", "timing.p50_us");
  out.planner_p99_us = r.number(timing, "p99_us", "timing.p99_us");
  out.planner_wall_p99_us = timing.contains("wall_p99_us")
                                ? r.number(timing, "wall_p99_us", "timing.wall_p99_us")
                                : out.planner_p99_us;
  out.planner_cycles = r.amount("planner_cycles");
  // Rows written before plan statuses were kept have none: all their cycles were normal. A
  // null one: the planner did not say (a program over the protocol).
  if (row.contains("plan_status") && row["plan_status"].is_null()) {
    out.plan_status_known = false;
    out.plan_status_unknown_cycles = out.planner_cycles;
  } else if (row.contains("plan_status")) {
    const json& cycles =
        r.object(r.object(row, "plan_status", "plan_status"), "cycles", "plan_status.cycles");
    for (std::size_t i = 0; i < core::kPlanStatusCount; ++i) {
      const std::string name(core::to_string(static_cast<core::PlanStatus>(i)));
      out.plan_status_cycles[i] =
          cycles.contains(name) ? r.amount(cycles, name, "plan_status.cycles." + name) : 0.0;
    }
    out.plan_status_unknown_cycles = cycles.contains("unknown")
                                         ? r.amount(cycles, "unknown", "plan_status.cycles.unknown")
                                         : 0.0;
    const json& status = row["plan_status"];
    if (status.contains("lane_changes_declined")) {
      const json& d =
          r.object(status, "lane_changes_declined", "plan_status.lane_changes_declined");
      out.changes_declined = std::array<double, 2>{
          r.amount(d, "for_cost", "plan_status.lane_changes_declined.for_cost"),
          r.amount(d, "for_safety", "plan_status.lane_changes_declined.for_safety")};
    }
  }
  out.ended_early = row.contains("ended_early") && !row["ended_early"].is_null();
  return out;
}

const MetricInfo& info(Metric m) {
  static const std::array<MetricInfo, kMetricCount> infos = {{
      {"mean_speed_mph", "mean speed", "mph", true},
      {"incidents_per_100mi", "incidents", "/100 mi", false},
      {"collisions_per_100mi", "collisions", "/100 mi", false},
      {"at_fault_collisions_per_100mi", "at-fault collisions", "/100 mi", false},
      {"near_misses_per_100mi", "near misses", "/100 mi", false},
  }};
  return infos[static_cast<std::size_t>(m)];
}

const std::array<Metric, kMetricCount>& all_metrics() {
  static const std::array<Metric, kMetricCount> all = {
      Metric::mean_speed_mph, Metric::incidents_per_100mi, Metric::collisions_per_100mi,
      Metric::at_fault_collisions_per_100mi, Metric::near_misses_per_100mi};
  return all;
}

std::optional<Metric> parse_metric(std::string_view name) {
  for (const Metric m : all_metrics()) {
    if (info(m).name == name) return m;
  }
  return std::nullopt;
}

MetricTerms terms(Metric m, const RunRow& r) {
  const auto rate = [&](double events) { return MetricTerms{100.0 * events, r.miles}; };
  switch (m) {
    case Metric::mean_speed_mph:
      return {r.miles, r.seconds / kSecondsPerHour};
    case Metric::incidents_per_100mi:
      return rate(r.incidents);
    case Metric::collisions_per_100mi:
      return rate(r.collisions);
    case Metric::at_fault_collisions_per_100mi:
      return rate(r.at_fault_collisions);
    case Metric::near_misses_per_100mi:
      return rate(r.near_misses);
  }
  return {};
}

bool available(Metric m, const std::vector<const RunRow*>& runs) {
  return unavailable_reason(m, runs).empty();
}

std::string unavailable_reason(Metric m, const std::vector<const RunRow*>& runs) {
  const bool collisions =
      m == Metric::collisions_per_100mi || m == Metric::at_fault_collisions_per_100mi;
  for (const RunRow* r : runs) {
    if (collisions && !r->contacts_known) {
      return "rows written before collisions were counted as contacts (they counted one per "
             "second of contact): bench again to compare collisions";
    }
    if (m == Metric::near_misses_per_100mi && !r->has_safety) {
      return "rows written before near misses were measured";
    }
  }
  return {};
}

double value(Metric m, const std::vector<const RunRow*>& runs) {
  double num = 0.0, den = 0.0;
  for (const RunRow* r : runs) {
    const MetricTerms t = terms(m, *r);
    num += t.numerator;
    den += t.denominator;
  }
  return den > 0.0 ? num / den : 0.0;
}

double value(Metric m, const RunRow& run) {
  const MetricTerms t = terms(m, run);
  return t.denominator > 0.0 ? t.numerator / t.denominator : 0.0;
}

}  // namespace overtake::eval
