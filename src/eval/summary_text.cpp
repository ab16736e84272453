// The bench summary as text: summary.csv, pairs.csv and summary.md, from the rows and pairs
// summary.cpp makes.

#include <cstdio>
#include <string>
#include <vector>

#include "overtake/eval/stats.hpp"
#include "overtake/eval/summary.hpp"

namespace overtake::eval {

namespace {

using nlohmann::json;

std::string kind_name(std::size_t k) {
  return std::string(sim::to_string(static_cast<sim::CollisionKind>(k)));
}

std::string incident_name(std::size_t t) {
  return std::string(sim::to_string(static_cast<sim::IncidentType>(t)));
}

std::string join_csv(const std::vector<std::string>& fields) {
  std::string line;
  for (const auto& f : fields) {
    if (!line.empty()) line += ',';
    line += f;
  }
  return line + "\n";
}

const json& null_json() {
  static const json null = nullptr;
  return null;
}

/// v[key] of an object, or null (for a part of a row that is null).
const json& member(const json& v, const char* key) {
  return v.is_object() && v.contains(key) ? v[key] : null_json();
}

/// pair[i] of an interval, or null.
const json& end_of(const json& pair, int i) {
  return pair.is_array() && pair.size() == 2 ? pair[static_cast<std::size_t>(i)] : null_json();
}

/// A number for CSV: empty for null.
std::string csv_number(const json& v, int decimals) {
  return v.is_number() ? fixed(v.get<double>(), decimals) : std::string();
}

/// "x (lo–hi)" for a value with an interval (just "x" without one).
std::string with_ci(const json& v, const json& ci, int decimals) {
  if (!v.is_number()) return "–";
  std::string s = fixed(v.get<double>(), decimals);
  if (ci.is_array()) {
    s += " (" + fixed(ci[0].get<double>(), decimals) + "–" + fixed(ci[1].get<double>(), decimals) +
         ")";
  }
  return s;
}

/// A rate with its interval; with no event "0.00 (≤ hi)", its one-sided upper bound.
std::string rate_cell(const json& v, const json& ci, int decimals) {
  if (v.is_number() && v.get<double>() == 0.0 && ci.is_array()) {
    return fixed(0.0, decimals) + " (≤ " + fixed(ci[1].get<double>(), decimals) + ")";
  }
  return with_ci(v, ci, decimals);
}

std::string seconds_or_dash(const json& v) {
  return v.is_number() ? fixed(v.get<double>(), 2) : "–";
}

std::string percent(double share, int decimals = 1) {
  return fixed(100.0 * share, decimals) + "%";
}

/// "least-bad % / fallback %" of a plan_status_share; "–" when unknown (null).
std::string status_cells(const json& share) {
  if (share.is_null()) return "–";
  return percent(share["least_bad"]) + " / " + percent(share["fallback"]);
}

/// A paired difference: "+0.27 (+0.05, +0.49) **better**" (the verdict only when beyond
/// noise), "+0.27 (too few seeds)".
std::string difference_cell(const json& f, int decimals) {
  if (f.is_null()) return "–";
  std::string s = signed_fixed(f["difference"].get<double>(), decimals);
  if (!f["ci"].is_array()) return s + " (" + f["verdict"].get<std::string>() + ")";
  s += " (" + signed_fixed(f["ci"][0].get<double>(), decimals) + ", " +
       signed_fixed(f["ci"][1].get<double>(), decimals) + ")";
  const std::string v = f["verdict"].is_string() ? f["verdict"].get<std::string>() : "";
  if (v == "better" || v == "worse") s += " **" + v + "**";
  return s;
}

/// "0.62 (0.45–0.78)"
std::string chance_cell(const json& f) {
  if (f.is_null() || !f["probability_of_improvement"].is_number()) return "–";
  return with_ci(f["probability_of_improvement"], f["probability_of_improvement_ci"], 2);
}

}  // namespace

std::string summary_csv(const json& rows) {
  std::vector<std::string> header{"policy",
                                  "traffic",
                                  "runs",
                                  "total_miles",
                                  "mean_speed_mph",
                                  "incidents",
                                  "incidents_per_100mi"};
  for (std::size_t t = 0; t < sim::kIncidentTypeCount; ++t)
    header.push_back(incident_name(t) + "_per_100mi");
  for (const char* h :
       {"incident_free_miles_median", "incident_free_miles_worst", "peak_acceleration_mps2",
        "peak_jerk_mps3", "peak_strict_acceleration_mps2", "peak_strict_jerk_mps3",
        "planner_p50_us_median", "planner_p99_us_worst", "planner_wall_p99_us_worst",
        "least_bad_cycle_share", "fallback_cycle_share", "runs_ended_early",
        // Added with intervals, collision classes and near misses (after the older columns, so
        // that scripts reading columns by position keep working).
        "mean_speed_mph_lo", "mean_speed_mph_hi", "incidents_per_100mi_lo",
        "incidents_per_100mi_hi", "collisions_per_100mi_lo", "collisions_per_100mi_hi",
        "at_fault_collisions", "at_fault_collisions_per_100mi", "at_fault_collisions_per_100mi_lo",
        "at_fault_collisions_per_100mi_hi", "incident_free_miles_median_lo",
        "incident_free_miles_median_hi", "near_misses", "near_misses_per_100mi",
        "near_misses_per_100mi_lo", "near_misses_per_100mi_hi", "min_ttc_ahead_s",
        "min_ttc_entering_s", "min_time_headway_s", "share_ttc_below", "share_headway_below",
        "seeds_to_halve_mean_speed", "seeds_to_halve_incidents", "seeds_to_halve_at_fault"}) {
    header.emplace_back(h);
  }
  for (std::size_t k = 0; k < sim::kCollisionKindCount; ++k)
    header.push_back("collisions_" + kind_name(k));
  // Added with collisions counted as contacts.
  for (const char* h : {"collisions", "collisions_per_100mi", "rubric_collision_incidents"}) {
    header.emplace_back(h);
  }
  std::string out = join_csv(header);
  for (const json& r : rows) {
    std::vector<std::string> f{r["policy"].get<std::string>(),
                               r["traffic"].get<std::string>(),
                               std::to_string(r["runs"].get<std::size_t>()),
                               fixed(r["total_miles"], 3),
                               fixed(r["mean_speed_mph"], 3),
                               fixed(r["incidents"], 0),
                               fixed(r["incidents_per_100mi"], 3)};
    for (std::size_t t = 0; t < sim::kIncidentTypeCount; ++t)
      f.push_back(fixed(r["incidents_per_100mi_by_type"][incident_name(t)], 3));
    for (const char* k :
         {"incident_free_miles_median", "incident_free_miles_worst", "peak_acceleration_mps2",
          "peak_jerk_mps3", "peak_strict_acceleration_mps2", "peak_strict_jerk_mps3"}) {
      f.push_back(fixed(r[k], 3));
    }
    f.push_back(fixed(r["timing"]["planner_p50_us_median"], 1));
    f.push_back(fixed(r["timing"]["planner_p99_us_worst"], 1));
    f.push_back(fixed(r["timing"]["planner_wall_p99_us_worst"], 1));
    const json& status = r["plan_status_share"];
    f.push_back(status.is_null() ? std::string() : fixed(status["least_bad"], 5));
    f.push_back(status.is_null() ? std::string() : fixed(status["fallback"], 5));
    f.push_back(std::to_string(r["runs_ended_early"].get<std::size_t>()));
    const json& c = r["collisions"];
    const json& nm = r["near_misses"];
    f.push_back(csv_number(end_of(r["mean_speed_mph_ci"], 0), 3));
    f.push_back(csv_number(end_of(r["mean_speed_mph_ci"], 1), 3));
    f.push_back(csv_number(end_of(r["incidents_per_100mi_ci"], 0), 3));
    f.push_back(csv_number(end_of(r["incidents_per_100mi_ci"], 1), 3));
    f.push_back(csv_number(end_of(member(c, "per_100mi_ci"), 0), 3));
    f.push_back(csv_number(end_of(member(c, "per_100mi_ci"), 1), 3));
    f.push_back(csv_number(member(c, "at_fault"), 0));
    f.push_back(csv_number(member(c, "at_fault_per_100mi"), 3));
    f.push_back(csv_number(end_of(member(c, "at_fault_per_100mi_ci"), 0), 3));
    f.push_back(csv_number(end_of(member(c, "at_fault_per_100mi_ci"), 1), 3));
    f.push_back(csv_number(end_of(r["incident_free_miles_median_ci"], 0), 3));
    f.push_back(csv_number(end_of(r["incident_free_miles_median_ci"], 1), 3));
    f.push_back(csv_number(member(nm, "episodes"), 0));
    f.push_back(csv_number(member(nm, "per_100mi"), 3));
    f.push_back(csv_number(end_of(member(nm, "per_100mi_ci"), 0), 3));
    f.push_back(csv_number(end_of(member(nm, "per_100mi_ci"), 1), 3));
    f.push_back(csv_number(member(nm, "min_ttc_ahead_s"), 3));
    f.push_back(csv_number(member(nm, "min_ttc_entering_s"), 3));
    f.push_back(csv_number(member(nm, "min_time_headway_s"), 3));
    f.push_back(csv_number(member(nm, "share_ttc_below"), 5));
    f.push_back(csv_number(member(nm, "share_headway_below"), 5));
    const json& prec = r["precision"];
    for (const char* k :
         {"mean_speed_mph", "incidents_per_100mi", "at_fault_collisions_per_100mi"}) {
      f.push_back(csv_number(member(prec[k], "seeds_to_halve"), 0));
    }
    for (std::size_t k = 0; k < sim::kCollisionKindCount; ++k) {
      f.push_back(csv_number(member(member(c, "by_kind"), kind_name(k).c_str()), 0));
    }
    f.push_back(csv_number(member(c, "total"), 0));
    f.push_back(csv_number(member(c, "per_100mi"), 3));
    f.push_back(csv_number(member(c, "rubric_incidents"), 0));
    out += join_csv(f);
  }
  return out;
}

std::string pairs_csv(const json& pairs) {
  std::vector<std::string> header{"traffic", "policy", "versus", "seeds"};
  // The older columns first, then those added with tests and their correction.
  const std::array<const char*, 5> older = {"_difference", "_lo", "_hi",
                                            "_probability_of_improvement", "_verdict"};
  const std::array<const char*, 4> added = {"_p_value", "_p_adjusted",
                                            "_probability_of_improvement_lo",
                                            "_probability_of_improvement_hi"};
  for (const Metric m : all_metrics()) {
    for (const char* suffix : older) header.push_back(std::string(info(m).name) + suffix);
  }
  for (const Metric m : all_metrics()) {
    for (const char* suffix : added) header.push_back(std::string(info(m).name) + suffix);
  }
  std::string out = join_csv(header);
  for (const json& p : pairs) {
    std::vector<std::string> f{p["traffic"].get<std::string>(), p["policy"].get<std::string>(),
                               p["versus"].get<std::string>(),
                               std::to_string(p["seeds"].get<std::size_t>())};
    for (const Metric m : all_metrics()) {
      const json& fig = p["figures"][std::string(info(m).name)];
      f.push_back(csv_number(member(fig, "difference"), 4));
      f.push_back(csv_number(end_of(member(fig, "ci"), 0), 4));
      f.push_back(csv_number(end_of(member(fig, "ci"), 1), 4));
      f.push_back(csv_number(member(fig, "probability_of_improvement"), 3));
      const json& v = member(fig, "verdict");
      f.push_back(v.is_string() ? v.get<std::string>() : std::string());
    }
    for (const Metric m : all_metrics()) {
      const json& fig = p["figures"][std::string(info(m).name)];
      f.push_back(csv_number(member(fig, "p_value"), 6));
      f.push_back(csv_number(member(fig, "p_adjusted"), 6));
      f.push_back(csv_number(end_of(member(fig, "probability_of_improvement_ci"), 0), 3));
      f.push_back(csv_number(end_of(member(fig, "probability_of_improvement_ci"), 1), 3));
    }
    out += join_csv(f);
  }
  return out;
}

namespace {

// The first cells of a row of the summary's tables.
std::string row_head(const std::string& p, const std::string& t) {
  return "| " + p + " | " + t + " | ";
}

// Speed and incidents, a row per policy and traffic.
std::string speed_table(const json& rows) {
  std::string out;
  out +=
      "Speed and incidents (95% intervals over the seeds: bootstrap-t for speed, order statistics "
      "for the median, overdispersed exact for the rates; a rate with no event: 0 (≤ its "
      "one-sided 95% upper bound); collisions are contacts, one per car touched; "
      "docs/evaluation.md)\n\n"
      "| policy | traffic | runs | miles | mean mph | incidents /100 mi | collisions /100 mi | "
      "at fault /100 mi | speeding | max acc | max jerk | outside lane | incident-free mi, "
      "median / worst |\n"
      "|---|---|---:|---:|---|---|---|---|---:|---:|---:|---:|---|\n";
  for (const json& r : rows) {
    const json& by = r["incidents_per_100mi_by_type"];
    const json& c = r["collisions"];
    out += row_head(r["policy"], r["traffic"]) + std::to_string(r["runs"].get<std::size_t>()) +
           " | " + fixed(r["total_miles"], 1) + " | " +
           with_ci(r["mean_speed_mph"], r["mean_speed_mph_ci"], 2) + " | " +
           rate_cell(r["incidents_per_100mi"], r["incidents_per_100mi_ci"], 2) + " | " +
           rate_cell(member(c, "per_100mi"), member(c, "per_100mi_ci"), 2) + " | " +
           rate_cell(member(c, "at_fault_per_100mi"), member(c, "at_fault_per_100mi_ci"), 2);
    for (const char* type : {"speeding", "max_acceleration", "max_jerk", "outside_lane"}) {
      out += " | " + fixed(by[type], 1);
    }
    out += " | " + with_ci(r["incident_free_miles_median"], r["incident_free_miles_median_ci"], 2) +
           " / " + fixed(r["incident_free_miles_worst"], 2) + " |\n";
  }
  return out;
}

// Near misses, for the rows that measure them (nothing when none does).
std::string near_miss_table(const json& rows) {
  std::string out;
  const json* any_near = nullptr;
  for (const json& r : rows) {
    if (!r["near_misses"].is_null()) any_near = &r["near_misses"];
  }
  if (any_near) {
    const std::string ttc = fixed((*any_near)["ttc_threshold_s"], 1);
    const std::string gap = fixed((*any_near)["headway_threshold_s"], 1);
    out +=
        "\nNear misses (least over the runs; shares of the time; the time gap is bumper to "
        "bumper; an episode: TTC below " +
        ttc +
        " s without a contact)\n\n"
        "| policy | traffic | least TTC ahead (s) | least TTC entering a lane (s) | least "
        "time gap (s) | time TTC < " +
        ttc + " s | time gap < " + gap +
        " s | near misses /100 mi |\n"
        "|---|---|---:|---:|---:|---:|---:|---|\n";
    for (const json& r : rows) {
      const json& nm = r["near_misses"];
      if (nm.is_null()) continue;
      out += row_head(r["policy"], r["traffic"]) + seconds_or_dash(nm["min_ttc_ahead_s"]) + " | " +
             seconds_or_dash(nm["min_ttc_entering_s"]) + " | " +
             seconds_or_dash(nm["min_time_headway_s"]) + " | " + percent(nm["share_ttc_below"], 2) +
             " | " + percent(nm["share_headway_below"], 1) + " | " +
             rate_cell(nm["per_100mi"], nm["per_100mi_ci"], 2) + " |\n";
    }
  }
  return out;
}

// Collisions by kind, for the rows that count contacts.
std::string collision_kind_table(const json& rows) {
  std::string out;
  bool classified = false;
  for (const json& r : rows) classified = classified || !r["collisions"].is_null();
  if (classified) {
    out +=
        "\nCollisions by kind (contacts; whose fault: docs/evaluation.md; the rubric counts a "
        "collision incident for every second of contact)\n\n| policy | traffic | "
        "collisions | at fault |";
    for (std::size_t k = 0; k < sim::kCollisionKindCount; ++k) out += " " + kind_name(k) + " |";
    out += " rubric's collision incidents |\n|---|---|---:|---:|";
    for (std::size_t k = 0; k < sim::kCollisionKindCount; ++k) out += "---:|";
    out += "---:|\n";
    for (const json& r : rows) {
      const json& c = r["collisions"];
      if (c.is_null()) continue;
      out += row_head(r["policy"], r["traffic"]) + fixed(c["total"], 0) + " | " +
             fixed(c["at_fault"], 0) + " |";
      for (std::size_t k = 0; k < sim::kCollisionKindCount; ++k) {
        out += " " + fixed(c["by_kind"][kind_name(k)], 0) + " |";
      }
      out += " " + fixed(c["rubric_incidents"], 0) + " |\n";
    }
  }
  return out;
}

// Comfort and the planner.
std::string comfort_table(const json& rows) {
  std::string out;
  out +=
      "\nComfort and the planner\n\n"
      "| policy | traffic | peak acc / jerk (rubric) | peak acc / jerk (strict) | planner CPU us "
      "(p50 / p99) | cycles least-bad / fallback | ended early |\n"
      "|---|---|---|---|---|---|---:|\n";
  for (const json& r : rows) {
    out += row_head(r["policy"], r["traffic"]) + fixed(r["peak_acceleration_mps2"], 1) + " / " +
           fixed(r["peak_jerk_mps3"], 1) + " | " + fixed(r["peak_strict_acceleration_mps2"], 1) +
           " / " + fixed(r["peak_strict_jerk_mps3"], 1) + " | " +
           fixed(r["timing"]["planner_p50_us_median"], 0) + " / " +
           fixed(r["timing"]["planner_p99_us_worst"], 0) + " | " +
           status_cells(r["plan_status_share"]) + " | " +
           std::to_string(r["runs_ended_early"].get<std::size_t>()) + " |\n";
  }
  return out;
}

// The paired comparisons (nothing without pairs).
std::string pairs_table(const json& pairs) {
  std::string out;
  if (!pairs.empty()) {
    out +=
        "\nPaired comparisons (the same seeds; A - B with its 95% interval over the seeds; "
        "**better** or **worse** when its test is significant at 5% family-wise, Holm over "
        "all " +
        std::to_string(family_size(pairs)) +
        " tests of this table's figures (paired t-test for speed, exact sign-flip test over "
        "seeds for the rates); no verdict below " +
        std::to_string(kMinSeeds) +
        " seeds; P: the probability of improvement, P(A better than B) over all pairs of "
        "runs, with its 95% interval)\n\n"
        "| traffic | A vs B | seeds | mean mph | P | incidents /100 mi | P | at fault /100 mi "
        "| P |\n|---|---|---:|---|---|---|---|---|---|\n";
    for (const json& p : pairs) {
      const json& f = p["figures"];
      out += "| " + p["traffic"].get<std::string>() + " | " + p["policy"].get<std::string>() +
             " vs " + p["versus"].get<std::string>() + " | " +
             std::to_string(p["seeds"].get<std::size_t>()) + " | " +
             difference_cell(f["mean_speed_mph"], 2) + " | " + chance_cell(f["mean_speed_mph"]) +
             " | " + difference_cell(f["incidents_per_100mi"], 2) + " | " +
             chance_cell(f["incidents_per_100mi"]) + " | " +
             difference_cell(f["at_fault_collisions_per_100mi"], 2) + " | " +
             chance_cell(f["at_fault_collisions_per_100mi"]) + " |\n";
    }
  }
  return out;
}

// How many seeds each interval would need to halve.
std::string precision_table(const json& rows) {
  std::string out;
  out +=
      "\nHow many seeds (± half the 95% interval; the seeds that would halve it, by the same "
      "method, if the spread stayed as it is)\n\n"
      "| policy | traffic | runs | mean mph ± | seeds to halve | incidents /100 mi ± | seeds to "
      "halve | at fault /100 mi ± | seeds to halve |\n"
      "|---|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const json& r : rows) {
    const json& p = r["precision"];
    const auto cells = [&](const json& x, int decimals) {
      if (x.is_null()) return std::string("– | –");
      return fixed(x["half_width"], decimals) + " | " +
             std::to_string(x["seeds_to_halve"].get<std::size_t>());
    };
    out += row_head(r["policy"], r["traffic"]) + std::to_string(r["runs"].get<std::size_t>()) +
           " | " + cells(p["mean_speed_mph"], 2) + " | " + cells(p["incidents_per_100mi"], 2) +
           " | " + cells(p["at_fault_collisions_per_100mi"], 2) + " |\n";
  }
  return out;
}

// The notes under the tables: missing intervals and figures, and the rows' warnings.
std::string notes_of(const json& rows) {
  std::string notes;
  for (const json& r : rows) {
    const std::string who =
        r["policy"].get<std::string>() + " / " + r["traffic"].get<std::string>();
    if (r["intervals"].is_string())
      notes += "- " + who + ": no intervals, " + r["intervals"].get<std::string>() + "\n";
    if (r["collisions"].is_null()) {
      notes += "- " + who +
               ": no collision figures (rows written before collisions were counted as "
               "contacts)\n";
    }
    for (const json& w : r["warnings"]) notes += "- " + who + ": " + w.get<std::string>() + "\n";
  }
  return notes.empty() ? std::string() : "\nNotes\n\n" + notes;
}

}  // namespace

std::string summary_markdown(const json& rows, const json& pairs) {
  return speed_table(rows) + near_miss_table(rows) + collision_kind_table(rows) +
         comfort_table(rows) + pairs_table(pairs) + precision_table(rows) + notes_of(rows);
}

}  // namespace overtake::eval
