// The bench's summary: per policy and traffic profile, the runs' figures summed up (miles,
// speed, incidents per 100 miles, incident-free distance, peaks, planner time, plan
// statuses), as JSON rows, CSV and Markdown.

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "overtake/app/bench.hpp"
#include "overtake/core/plan.hpp"
#include "overtake/core/units.hpp"
#include "overtake/sim/referee.hpp"

namespace overtake::app {
namespace {

using nlohmann::json;

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string fmt(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

// A share (0-1) as a percentage with one decimal, e.g. "12.5%".
std::string percent(double share) {
  return fmt(100.0 * share, 1) + "%";
}

const std::vector<std::string>& incident_types() {
  static const std::vector<std::string> types = [] {
    std::vector<std::string> t;
    for (std::size_t i = 0; i < sim::kIncidentTypeCount; ++i) {
      t.emplace_back(sim::to_string(static_cast<sim::IncidentType>(i)));
    }
    return t;
  }();
  return types;
}

}  // namespace

json summarize_bench(const std::vector<json>& runs, const std::vector<std::string>& policies,
                     const std::vector<std::string>& traffic) {
  json rows = json::array();
  for (const auto& p : policies) {
    for (const auto& t : traffic) {
      std::vector<const json*> mine;
      for (const json& r : runs) {
        if (r["config"]["policy"] == p && r["config"]["traffic"] == t) mine.push_back(&r);
      }
      if (mine.empty()) continue;
      double miles = 0.0, seconds = 0.0, peak_acc = 0.0, peak_jerk = 0.0, strict_acc = 0.0,
             strict_jerk = 0.0, worst_p99 = 0.0, worst_wall_p99 = 0.0;
      std::vector<double> free_miles, p50s;
      std::map<std::string, double> counts;
      std::map<std::string, double> status_cycles;  // by plan status, over every run
      double cycles = 0.0;
      std::size_t ended_early = 0;
      for (const json* r : mine) {
        // Rows written before plan statuses were kept have none: all their cycles count as
        // normal.
        const json none = json::object();
        const json& statuses = r->contains("plan_status") ? (*r)["plan_status"]["cycles"] : none;
        for (std::size_t i = 0; i < core::kPlanStatusCount; ++i) {
          const std::string name(core::to_string(static_cast<core::PlanStatus>(i)));
          status_cycles[name] += statuses.value(name, 0.0);
        }
        cycles += (*r)["planner_cycles"].get<double>();
        if (!(*r)["ended_early"].is_null()) ++ended_early;
        miles += (*r)["distance_miles"].get<double>();
        seconds += (*r)["duration_s"].get<double>();
        free_miles.push_back((*r)["best_incident_free_miles"].get<double>());
        for (const auto& type : incident_types())
          counts[type] += (*r)["incident_counts"][type].get<double>();
        const json& pk = (*r)["peak"];
        peak_acc = std::max(peak_acc, pk["acceleration_mps2"].get<double>());
        peak_jerk = std::max(peak_jerk, pk["jerk_mps3"].get<double>());
        strict_acc = std::max(strict_acc, pk["strict_acceleration_mps2"].get<double>());
        strict_jerk = std::max(strict_jerk, pk["strict_jerk_mps3"].get<double>());
        p50s.push_back((*r)["timing"]["p50_us"].get<double>());
        const json& timing = (*r)["timing"];
        worst_p99 = std::max(worst_p99, timing["p99_us"].get<double>());
        worst_wall_p99 =
            std::max(worst_wall_p99, timing.value("wall_p99_us", timing["p99_us"].get<double>()));
      }
      json per100 = json::object();
      double total_incidents = 0.0;
      for (const auto& type : incident_types()) {
        per100[type] = miles > 0 ? 100.0 * counts[type] / miles : 0.0;
        total_incidents += counts[type];
      }
      json status_share = json::object();
      for (std::size_t i = 0; i < core::kPlanStatusCount; ++i) {
        const std::string name(core::to_string(static_cast<core::PlanStatus>(i)));
        status_share[name] = cycles > 0 ? status_cycles[name] / cycles : 0.0;
      }
      // Earlier rows without statuses: their cycles are normal ones.
      status_share["normal"] = cycles > 0 ? 1.0 - status_share["least_bad"].get<double>() -
                                                status_share["fallback"].get<double>()
                                          : 0.0;
      rows.push_back(
          {{"policy", p},
           {"traffic", t},
           {"runs", mine.size()},
           {"total_miles", miles},
           {"mean_speed_mph",
            seconds > 0 ? miles * core::kMetresPerMile / seconds * core::kMphPerMps : 0.0},
           {"incidents", total_incidents},
           {"incidents_per_100mi", miles > 0 ? 100.0 * total_incidents / miles : 0.0},
           {"incidents_per_100mi_by_type", per100},
           {"incident_free_miles_median", median(free_miles)},
           {"incident_free_miles_worst", *std::min_element(free_miles.begin(), free_miles.end())},
           {"peak_acceleration_mps2", peak_acc},
           {"peak_jerk_mps3", peak_jerk},
           {"peak_strict_acceleration_mps2", strict_acc},
           {"peak_strict_jerk_mps3", strict_jerk},
           {"plan_status_share", status_share},
           {"runs_ended_early", ended_early},
           {"timing",
            {{"planner_p50_us_median", median(p50s)},
             {"planner_p99_us_worst", worst_p99},
             {"planner_wall_p99_us_worst", worst_wall_p99}}}});
    }
  }
  return rows;
}

std::string summary_csv(const json& rows) {
  auto join = [](const std::vector<std::string>& fields) {
    std::string line;
    for (const auto& f : fields) {
      if (!line.empty()) line += ',';
      line += f;
    }
    line += '\n';
    return line;
  };
  std::vector<std::string> header{"policy",
                                  "traffic",
                                  "runs",
                                  "total_miles",
                                  "mean_speed_mph",
                                  "incidents",
                                  "incidents_per_100mi"};
  for (const auto& type : incident_types()) header.push_back(type + std::string("_per_100mi"));
  for (const char* h :
       {"incident_free_miles_median", "incident_free_miles_worst", "peak_acceleration_mps2",
        "peak_jerk_mps3", "peak_strict_acceleration_mps2", "peak_strict_jerk_mps3",
        "planner_p50_us_median", "planner_p99_us_worst", "planner_wall_p99_us_worst",
        "least_bad_cycle_share", "fallback_cycle_share", "runs_ended_early"}) {
    header.emplace_back(h);
  }
  std::string out = join(header);
  for (const json& r : rows) {
    std::vector<std::string> f{r["policy"].get<std::string>(),
                               r["traffic"].get<std::string>(),
                               std::to_string(r["runs"].get<std::size_t>()),
                               fmt(r["total_miles"], 3),
                               fmt(r["mean_speed_mph"], 3),
                               fmt(r["incidents"], 0),
                               fmt(r["incidents_per_100mi"], 3)};
    for (const auto& type : incident_types())
      f.push_back(fmt(r["incidents_per_100mi_by_type"][type], 3));
    for (const char* k :
         {"incident_free_miles_median", "incident_free_miles_worst", "peak_acceleration_mps2",
          "peak_jerk_mps3", "peak_strict_acceleration_mps2", "peak_strict_jerk_mps3"}) {
      f.push_back(fmt(r[k], 3));
    }
    f.push_back(fmt(r["timing"]["planner_p50_us_median"], 1));
    f.push_back(fmt(r["timing"]["planner_p99_us_worst"], 1));
    f.push_back(fmt(r["timing"]["planner_wall_p99_us_worst"], 1));
    f.push_back(fmt(r["plan_status_share"]["least_bad"], 5));
    f.push_back(fmt(r["plan_status_share"]["fallback"], 5));
    f.push_back(std::to_string(r["runs_ended_early"].get<std::size_t>()));
    out += join(f);
  }
  return out;
}

std::string summary_markdown(const json& rows) {
  std::string out =
      "| policy | traffic | runs | miles | mean mph | incidents /100 mi | collision | speeding | "
      "max acc | "
      "max jerk | outside lane | incident-free mi (median / worst) | peak acc / jerk (rubric) | "
      "peak acc / jerk (strict) | planner CPU us (p50 / p99) | cycles least-bad / fallback | "
      "ended early |\n"
      "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|---|---|---|---:|\n";
  for (const json& r : rows) {
    const json& by = r["incidents_per_100mi_by_type"];
    out += "| " + r["policy"].get<std::string>() + " | " + r["traffic"].get<std::string>() + " | " +
           std::to_string(r["runs"].get<std::size_t>()) + " | " + fmt(r["total_miles"], 1) + " | " +
           fmt(r["mean_speed_mph"], 2) + " | " + fmt(r["incidents_per_100mi"], 1);
    for (const auto& type : incident_types()) out += " | " + fmt(by[type], 1);
    out += " | " + fmt(r["incident_free_miles_median"], 2) + " / " +
           fmt(r["incident_free_miles_worst"], 2) + " | " + fmt(r["peak_acceleration_mps2"], 1) +
           " / " + fmt(r["peak_jerk_mps3"], 1) + " | " +
           fmt(r["peak_strict_acceleration_mps2"], 1) + " / " + fmt(r["peak_strict_jerk_mps3"], 1) +
           " | " + fmt(r["timing"]["planner_p50_us_median"], 0) + " / " +
           fmt(r["timing"]["planner_p99_us_worst"], 0) + " | " +
           percent(r["plan_status_share"]["least_bad"]) + " / " +
           percent(r["plan_status_share"]["fallback"]) + " | " +
           std::to_string(r["runs_ended_early"].get<std::size_t>()) + " |\n";
  }
  return out;
}

}  // namespace overtake::app
