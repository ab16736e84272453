#include "overtake/run/report.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "overtake/base/text.hpp"
#include "overtake/core/units.hpp"

namespace overtake::run {

using base::fixed_text;
namespace {

using nlohmann::json;

const char* value_unit(sim::IncidentType t) {
  switch (t) {
    case sim::IncidentType::collision:
      return "car_id";
    case sim::IncidentType::speeding:
      return "mph";
    case sim::IncidentType::max_acceleration:
      return "m/s^2";
    case sim::IncidentType::max_jerk:
      return "m/s^3";
    case sim::IncidentType::outside_lane:
      return "d_m";
  }
  return "";
}

double report_value(const sim::Incident& i) {
  return i.type == sim::IncidentType::speeding ? core::mps_to_mph(i.value) : i.value;
}

std::string steps_text(const RunProvenance& p) {
  if (p.steps_per_call > 0) return std::to_string(p.steps_per_call);
  return "random " + std::to_string(p.min_steps_per_call) + "-" +
         std::to_string(p.max_steps_per_call);
}

// Null when the planner never said how it planned (a program over the protocol): its cycles
// are not known to be normal. A run that mixes both keeps the known counts and adds how many
// were unknown (only then, so that other reports keep their bytes).
json plan_status_json(const sim::RunReport& r) {
  if (!r.plan_status_known()) return nullptr;
  json cycles = json::object();
  for (std::size_t i = 0; i < core::kPlanStatusCount; ++i) {
    cycles[std::string(core::to_string(static_cast<core::PlanStatus>(i)))] =
        r.plan_status_cycles[i];
  }
  if (r.plan_status_unknown_cycles > 0) cycles["unknown"] = r.plan_status_unknown_cycles;
  return {
      {"cycles", cycles},
      {"first_reason", r.first_plan_reason.empty() ? json(nullptr) : json(r.first_plan_reason)},
      {"lane_changes_declined",
       {{"for_cost", r.changes_declined_for_cost}, {"for_safety", r.changes_declined_for_safety}}}};
}

// A figure that may never have been measured (infinity): null in JSON.
json finite_or_null(double v) {
  return std::isfinite(v) ? json(v) : json(nullptr);
}

// The run's collisions, counted as contacts (one per car touched, however long), summed up by
// their classes.
struct CollisionCounts {
  int total = 0;
  int at_fault = 0;
  std::array<int, sim::kCollisionKindCount> by_kind{};
};

CollisionCounts count_collisions(const sim::RunReport& r) {
  CollisionCounts c;
  for (const sim::Contact& k : r.contacts) {
    ++c.total;
    ++c.by_kind[static_cast<std::size_t>(k.collision.kind)];
    if (k.collision.at_fault) ++c.at_fault;
  }
  return c;
}

std::string kind_name(std::size_t k) {
  return std::string(sim::to_string(static_cast<sim::CollisionKind>(k)));
}

json collisions_json(const sim::RunReport& r) {
  const CollisionCounts c = count_collisions(r);
  json by_kind = json::object();
  for (std::size_t k = 0; k < c.by_kind.size(); ++k) by_kind[kind_name(k)] = c.by_kind[k];
  json contacts = json::array();
  for (const sim::Contact& k : r.contacts) {
    contacts.push_back({{"car", k.car_id},
                        {"t_s", k.t_s},
                        {"end_t_s", k.end_t_s},
                        {"s_m", k.s_m},
                        {"lane", k.lane},
                        {"kind", sim::to_string(k.collision.kind)},
                        {"at_fault", k.collision.at_fault},
                        {"rubric_incidents", k.rubric_collisions}});
  }
  return {{"total", c.total},
          {"at_fault", c.at_fault},
          {"by_kind", by_kind},
          {"rubric_incidents",
           r.incident_counts[static_cast<std::size_t>(sim::IncidentType::collision)]},
          {"contacts", contacts}};
}

json safety_json(const sim::RunReport& r) {
  const sim::SafetySummary& s = r.safety;
  const double d = r.duration_s;
  return {{"min_ttc_ahead_s", finite_or_null(s.min_ttc_ahead_s)},
          {"min_ttc_entering_s", finite_or_null(s.min_ttc_entering_s)},
          {"min_time_headway_s", finite_or_null(s.min_headway_s)},
          {"time_ttc_below_s", s.ttc_below_s},
          {"share_ttc_below", d > 0 ? s.ttc_below_s / d : 0.0},
          {"time_headway_below_s", s.headway_below_s},
          {"share_headway_below", d > 0 ? s.headway_below_s / d : 0.0},
          {"near_miss_episodes", s.near_miss_episodes},
          {"ttc_threshold_s", s.ttc_threshold_s},
          {"headway_threshold_s", s.headway_threshold_s}};
}

std::string printf_string(const char* format, auto... args) {
  char buf[512];
  std::snprintf(buf, sizeof buf, format, args...);
  return buf;
}

}  // namespace

json incident_to_json(const sim::Incident& i) {
  json j = {{"type", sim::to_string(i.type)},
            {"t_s", i.t_s},
            {"s_m", i.s_m},
            {"lane", i.lane},
            {"value", report_value(i)},
            {"unit", value_unit(i.type)}};
  if (i.collision) {
    j["kind"] = sim::to_string(i.collision->kind);
    j["at_fault"] = i.collision->at_fault;
  }
  if (i.type == sim::IncidentType::collision && i.contact >= 0) j["contact"] = i.contact;
  return j;
}

std::string collision_text(const sim::CollisionClass& collision) {
  return std::string(sim::to_string(collision.kind)) +
         (collision.at_fault ? " (at fault)" : " (not at fault)");
}

sim::Incident contact_incident(const sim::Contact& k, int index) {
  sim::Incident i;
  i.type = sim::IncidentType::collision;
  i.t_s = k.t_s;
  i.s_m = k.s_m;
  i.lane = k.lane;
  i.value = k.car_id;
  i.collision = k.collision;
  i.contact = index;
  return i;
}

json report_to_json(const sim::RunReport& r, const RunProvenance& p) {
  json j = json::object();
  j["distance_miles"] = core::metres_to_miles(r.distance_m);
  j["duration_s"] = r.duration_s;
  j["mean_speed_mph"] = core::mps_to_mph(r.mean_speed_mps);
  j["best_incident_free_miles"] = core::metres_to_miles(r.best_incident_free_m);
  json counts = json::object();
  for (std::size_t i = 0; i < sim::kIncidentTypeCount; ++i) {
    counts[std::string(sim::to_string(static_cast<sim::IncidentType>(i)))] = r.incident_counts[i];
  }
  j["incident_counts"] = counts;
  j["exact_outside_lane"] = r.exact_outside_lane;
  json incidents = json::array();
  for (const sim::Incident& i : r.incidents) incidents.push_back(incident_to_json(i));
  j["incidents"] = incidents;
  j["collisions"] = collisions_json(r);
  j["safety"] = safety_json(r);
  j["peak"] = {{"speed_mph", core::mps_to_mph(r.peak.speed_mps)},
               {"acceleration_mps2", r.peak.acceleration_mps2},
               {"jerk_mps3", r.peak.jerk_mps3},
               {"strict_acceleration_mps2", r.peak.strict_acceleration_mps2},
               {"strict_jerk_mps3", r.peak.strict_jerk_mps3}};
  j["lane_changes"] = r.lane_changes;
  j["time_in_lane_s"] = r.time_in_lane_s;
  j["planner_cycles"] = r.planner_cycles;
  j["plan_status"] = plan_status_json(r);
  j["end"] = sim::to_string(r.outcome.end);
  const std::string early = sim::ended_early_text(r.outcome);
  j["ended_early"] = early.empty() ? json(nullptr) : json(early);
  j["timing"] = {{"clock", sim::to_string(r.timing.clock)},
                 {"p50_us", r.timing.p50_us},
                 {"p99_us", r.timing.p99_us},
                 {"max_us", r.timing.max_us},
                 {"wall_p99_us", r.timing.wall_p99_us},
                 {"wall_max_us", r.timing.wall_max_us}};
  j["config"] = {{"seed", p.seed},
                 {"policy", p.policy},
                 {"traffic", p.traffic},
                 {"map", {{"path", p.map_path}, {"hash", p.map_hash}}},
                 {"steps_per_call", steps_text(p)},
                 {"minutes", p.minutes},
                 {"params_hash", p.params_hash}};
  if (!p.scenario.empty()) j["config"]["scenario"] = p.scenario;
  if (r.warm_up) j["warm_up"] = warm_up_to_json(*r.warm_up);
  if (const std::string hint = map_hint(r, p); !hint.empty()) j["map_hint"] = hint;
  if (!p.planner.empty()) j["config"]["planner"] = json::parse(p.planner);
  if (!p.planner_log.empty()) j["config"]["planner_log"] = p.planner_log;
  return j;
}

std::string map_hint(const sim::RunReport& r, const RunProvenance& p) {
  if (p.planner.empty() && p.planner_url.empty()) return {};
  const double start_s = r.outcome.t_s - r.duration_s;
  const auto off =
      std::find_if(r.incidents.begin(), r.incidents.end(), [&](const sim::Incident& i) {
        return i.type == sim::IncidentType::outside_lane && i.t_s <= start_s + kMapHintWithinS;
      });
  if (off == r.incidents.end()) return {};
  return "the planner's path left the road " + fixed_text(off->t_s - start_s, 2) +
         " s after the start: a planner program reads its own map file, and may be driving "
         "another map than this run's (" +
         p.map_path + "); give overtake the map the program reads with --map FILE";
}

json warm_up_to_json(const sim::WarmUpResult& w) {
  const auto cycle = [](long c) { return c < 0 ? json(nullptr) : json(c); };
  return {{"cycles", w.cycles},
          {"played", w.played},
          {"from_run_start", w.from_run_start},
          {"in_step_cycles", w.in_step_cycles},
          {"in_step", w.in_step},
          {"in_step_after", w.in_step ? json(w.in_step_after) : json(nullptr)},
          {"matched", w.matched},
          {"first_difference", cycle(w.first_difference)},
          {"first_difference_t_s",
           w.first_difference < 0 ? json(nullptr) : json(w.first_difference_t_s)},
          {"last_difference", cycle(w.last_difference)}};
}

std::string warm_up_text(const sim::WarmUpResult& w) {
  std::string text = std::to_string(w.played) + " of " + std::to_string(w.cycles) +
                     " cycles told before the start" +
                     (w.from_run_start ? std::string(" (from the run's first)") : std::string());
  if (w.in_step) {
    text += ": in step after " + std::to_string(w.in_step_after) + " (" +
            std::to_string(w.in_step_cycles) + " answers in a row as recorded";
    if (w.first_difference < 0) text += "; every answer matched";
    return text + ")";
  }
  text += ": NOT IN STEP, reproduction not guaranteed (";
  if (w.played < w.cycles) return text + "the warm-up did not finish)";
  return text + std::to_string(w.matched) + " answers matched; the last differed at cycle " +
         std::to_string(w.last_difference + 1) + "; a longer --warm-up, or all, may help)";
}

namespace {

// The scorecard's first lines: who drove, where, and how the run ended.
void scorecard_head(std::ostream& os, const sim::RunReport& r, const RunProvenance& p) {
  if (!p.planner.empty()) {  // brought by a flag: a plugin, a Python planner, a program
    const json what = json::parse(p.planner);
    os << "overtake: " << what.value("kind", "planner") << " " << p.policy << " ("
       << what.value("source", "") << ")";
  } else if (p.planner_url.empty()) {
    os << "overtake drive: policy " << p.policy;
  } else {
    os << "overtake sim: planner " << (p.policy == p.planner_url ? "" : p.policy + " ") << "at "
       << p.planner_url;
  }
  os << ", " << p.traffic << " traffic, seed " << p.seed << ", map " << p.map_path << "\n";
  if (!p.planner.empty()) {
    const json what = json::parse(p.planner);
    if (what.value("network", "") == "host") {
      os << "  network            the host's: whatever listened on port " << what.value("port", 0)
         << " was taken for the planner\n";
    }
  }
  if (r.outcome.ended_early()) os << "  ENDED EARLY: " << sim::ended_early_text(r.outcome) << "\n";
  if (r.warm_up) os << "  warm-up            " << warm_up_text(*r.warm_up) << "\n";
  if (const std::string hint = map_hint(r, p); !hint.empty()) os << "  HINT: " << hint << "\n";
}

// Distance, speed, incidents and contacts.
void scorecard_counts(std::ostream& os, const sim::RunReport& r) {
  os << printf_string("  simulated         %8.1f min   distance %8.2f mi   mean speed %6.2f mph\n",
                      r.duration_s / 60.0, core::metres_to_miles(r.distance_m),
                      core::mps_to_mph(r.mean_speed_mps));
  os << printf_string("  best incident-free %7.2f mi    lane changes %d\n",
                      core::metres_to_miles(r.best_incident_free_m), r.lane_changes);
  int total = 0;
  for (int c : r.incident_counts) total += c;
  os << "  incidents          " << total << " (";
  for (std::size_t i = 0; i < sim::kIncidentTypeCount; ++i) {
    os << (i ? ", " : "") << sim::to_string(static_cast<sim::IncidentType>(i)) << " "
       << r.incident_counts[i];
  }
  os << ")\n";
  if (const CollisionCounts c = count_collisions(r); c.total > 0) {
    os << "  collisions         " << c.total << " contact" << (c.total == 1 ? "" : "s")
       << ": at fault " << c.at_fault << " (";
    const char* sep = "";
    for (std::size_t k = 0; k < c.by_kind.size(); ++k) {
      if (c.by_kind[k] == 0) continue;
      os << sep << kind_name(k) << " " << c.by_kind[k];
      sep = ", ";
    }
    os << "); the rubric's collision incidents, one per second of contact: "
       << r.incident_counts[static_cast<std::size_t>(sim::IncidentType::collision)] << "\n";
  }
}

// Near misses, the exact lane keeping, the peaks and the time per lane.
void scorecard_safety(std::ostream& os, const sim::RunReport& r) {
  const sim::SafetySummary& s = r.safety;
  const auto seconds = [](double v) {
    return std::isfinite(v) ? printf_string("%.2f s", v) : std::string("none");
  };
  const double d = r.duration_s > 0 ? r.duration_s : 1.0;
  os << "  near misses        least TTC ahead " << seconds(s.min_ttc_ahead_s)
     << ", entering a lane " << seconds(s.min_ttc_entering_s) << ", least time gap "
     << seconds(s.min_headway_s) << "\n";
  os << printf_string(
      "                     TTC < %.1f s %.2f%% of the time, time gap < %.1f s %.2f%%, %d "
      "near-miss episode%s\n",
      s.ttc_threshold_s, 100.0 * s.ttc_below_s / d, s.headway_threshold_s,
      100.0 * s.headway_below_s / d, s.near_miss_episodes, s.near_miss_episodes == 1 ? "" : "s");
  if (r.exact_outside_lane !=
      r.incident_counts[static_cast<std::size_t>(sim::IncidentType::outside_lane)]) {
    os << "  outside of lane on the exact d (not the rubric's): " << r.exact_outside_lane << "\n";
  }
  os << printf_string(
      "  peak, rubric       speed %.2f mph   acceleration %.2f m/s^2   jerk %.2f m/s^3\n",
      core::mps_to_mph(r.peak.speed_mps), r.peak.acceleration_mps2, r.peak.jerk_mps3);
  os << printf_string("  peak, strict 0.1 s acceleration %.2f m/s^2   jerk %.2f m/s^3\n",
                      r.peak.strict_acceleration_mps2, r.peak.strict_jerk_mps3);
  os << "  time per lane     ";
  for (std::size_t l = 0; l < r.time_in_lane_s.size(); ++l) {
    const double pct = r.duration_s > 0 ? 100.0 * r.time_in_lane_s[l] / r.duration_s : 0.0;
    os << printf_string(" %zu: %5.1f%%", l, pct);
  }
  os << "\n";
}

// The planner's time per cycle, and how it planned when it did not plan normally.
void scorecard_planner(std::ostream& os, const sim::RunReport& r) {
  os << printf_string(
      "  planner time       p50 %.1f us   p99 %.1f us   max %.1f us   (%ld cycles, %s)\n",
      r.timing.p50_us, r.timing.p99_us, r.timing.max_us, r.planner_cycles,
      r.timing.clock == sim::CycleClock::thread_cpu ? "thread CPU time"
                                                    : "round trip over the protocol, wall clock");
  if (r.timing.clock == sim::CycleClock::thread_cpu) {
    os << printf_string("  planner wall time  p99 %.1f us   max %.1f us\n", r.timing.wall_p99_us,
                        r.timing.wall_max_us);
  }
  const long unusual = r.plan_status_cycles[static_cast<std::size_t>(core::PlanStatus::least_bad)] +
                       r.plan_status_cycles[static_cast<std::size_t>(core::PlanStatus::fallback)];
  // Nothing when no cycle was left normal planning, or no cycle said how it planned (then
  // `unusual` is 0: unknown cycles are not counted by status). Shares are of the cycles whose
  // status is known.
  if (unusual > 0) {
    const long known = r.planner_cycles - r.plan_status_unknown_cycles;
    const auto share = [&](core::PlanStatus s) {
      const long n = r.plan_status_cycles[static_cast<std::size_t>(s)];
      return known > 0 ? 100.0 * static_cast<double>(n) / static_cast<double>(known) : 0.0;
    };
    os << printf_string(
        "  plan status        normal %.1f%%   least-bad %.1f%%   fallback %.1f%% of cycles\n",
        share(core::PlanStatus::normal), share(core::PlanStatus::least_bad),
        share(core::PlanStatus::fallback));
    os << "    first: " << r.first_plan_reason << "\n";
  }
  if (r.changes_declined_for_cost + r.changes_declined_for_safety > 0) {
    os << printf_string(
        "  changes declined   %ld for their cost, %ld for safety (chosen, not taken)\n",
        r.changes_declined_for_cost, r.changes_declined_for_safety);
  }
}

// The first incidents, one a line.
void scorecard_incidents(std::ostream& os, const sim::RunReport& r) {
  constexpr std::size_t kShown = 10;
  if (!r.incidents.empty()) {
    os << "  first incidents:\n";
    for (std::size_t i = 0; i < r.incidents.size() && i < kShown; ++i) {
      const sim::Incident& inc = r.incidents[i];
      os << printf_string("    t %8.2f s   s %8.1f m   lane %d   %-16s %.3f %s", inc.t_s, inc.s_m,
                          inc.lane, std::string(sim::to_string(inc.type)).c_str(),
                          report_value(inc), value_unit(inc.type));
      if (inc.collision) {
        os << "   " << collision_text(*inc.collision);
      }
      if (inc.type == sim::IncidentType::collision && inc.contact >= 0) {
        os << ", contact " << inc.contact + 1;
      }
      os << "\n";
    }
    if (r.incidents.size() > kShown) {
      os << "    ... and " << r.incidents.size() - kShown << " more (see --json)\n";
    }
  }
}

}  // namespace

std::string format_scorecard(const sim::RunReport& r, const RunProvenance& p) {
  std::ostringstream os;
  scorecard_head(os, r, p);
  scorecard_counts(os, r);
  scorecard_safety(os, r);
  scorecard_planner(os, r);
  scorecard_incidents(os, r);
  return os.str();
}

}  // namespace overtake::run
