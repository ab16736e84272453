#include "overtake/eval/summary.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <utility>

#include "overtake/eval/stats.hpp"

namespace overtake::eval {
namespace {

using nlohmann::json;

constexpr double kInf = std::numeric_limits<double>::infinity();

json pair_of(const Interval& i) {
  return json::array({i.lo, i.hi});
}

json finite_or_null(double v) {
  return std::isfinite(v) ? json(v) : json(nullptr);
}

std::string incident_name(std::size_t t) {
  return std::string(sim::to_string(static_cast<sim::IncidentType>(t)));
}
std::string kind_name(std::size_t k) {
  return std::string(sim::to_string(static_cast<sim::CollisionKind>(k)));
}

/// The (policy, traffic) groups in order: the given ones that have runs, then others found.
std::vector<std::pair<std::string, std::string>> groups_of(
    const std::vector<RunRow>& runs, const std::vector<std::string>& policies,
    const std::vector<std::string>& traffic) {
  std::vector<std::pair<std::string, std::string>> order;
  std::set<std::pair<std::string, std::string>> seen;
  const auto add = [&](const std::string& p, const std::string& t) {
    if (seen.insert({p, t}).second) order.emplace_back(p, t);
  };
  for (const auto& p : policies) {
    for (const auto& t : traffic) add(p, t);
  }
  for (const RunRow& r : runs) add(r.policy, r.traffic);
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& g : order) {
    const bool has = std::any_of(runs.begin(), runs.end(), [&](const RunRow& r) {
      return r.policy == g.first && r.traffic == g.second;
    });
    if (has) out.push_back(g);
  }
  return out;
}

BootstrapOptions bootstrap_for(const std::string& key) {
  BootstrapOptions o;
  o.seed = bootstrap_seed(key);
  return o;
}

/// An interval's precision: its half width and the seeds that would halve it.
json precision(const Interval& i, std::size_t seeds_to_halve) {
  return {{"half_width", 0.5 * i.width()}, {"seeds_to_halve", seeds_to_halve}};
}

json summary_row(const std::string& policy, const std::string& traffic,
                 const std::vector<const RunRow*>& mine) {
  const std::string key = policy + "|" + traffic;
  double miles = 0.0, seconds = 0.0, peak_acc = 0.0, peak_jerk = 0.0, strict_acc = 0.0,
         strict_jerk = 0.0, worst_p99 = 0.0, worst_wall_p99 = 0.0, known_cycles = 0.0;
  std::vector<double> free_miles, p50s, speed_num, speed_den;
  std::array<double, sim::kIncidentTypeCount> counts{};
  std::array<double, core::kPlanStatusCount> status_cycles{};
  bool some_unknown = false;  // a row, or some cycles of one, whose plan status is unknown
  std::size_t ended_early = 0;
  for (const RunRow* r : mine) {
    miles += r->miles;
    seconds += r->seconds;
    free_miles.push_back(r->best_incident_free_miles);
    for (std::size_t t = 0; t < counts.size(); ++t) counts[t] += r->incidents_by_type[t];
    peak_acc = std::max(peak_acc, r->peak_acceleration_mps2);
    peak_jerk = std::max(peak_jerk, r->peak_jerk_mps3);
    strict_acc = std::max(strict_acc, r->peak_strict_acceleration_mps2);
    strict_jerk = std::max(strict_jerk, r->peak_strict_jerk_mps3);
    p50s.push_back(r->planner_p50_us);
    worst_p99 = std::max(worst_p99, r->planner_p99_us);
    worst_wall_p99 = std::max(worst_wall_p99, r->planner_wall_p99_us);
    some_unknown = some_unknown || r->plan_status_unknown_cycles > 0 || !r->plan_status_known;
    if (r->plan_status_known) {
      known_cycles += r->planner_cycles - r->plan_status_unknown_cycles;
      for (std::size_t i = 0; i < status_cycles.size(); ++i)
        status_cycles[i] += r->plan_status_cycles[i];
    }
    if (r->ended_early) ++ended_early;
    const MetricTerms speed = terms(Metric::mean_speed_mph, *r);
    speed_num.push_back(speed.numerator);
    speed_den.push_back(speed.denominator);
  }
  const std::size_t n = mine.size();
  double total_incidents = 0.0;
  json per100 = json::object(), per100_ci = json::object();
  for (std::size_t t = 0; t < counts.size(); ++t) {
    per100[incident_name(t)] = miles > 0 ? 100.0 * counts[t] / miles : 0.0;
    per100_ci[incident_name(t)] = pair_of(rate_interval(counts[t], miles, 100.0));
    total_incidents += counts[t];
  }
  // The shares of the cycles whose status is known. Null when none is but some cycles are
  // unknown (a planner over the protocol does not say how it planned: its cycles are not
  // normal ones). A group that mixes both (it should not: one planner per policy) gets the
  // shares of the runs that say; those that do not are left out, not counted as normal.
  json status_share = nullptr;
  if (known_cycles > 0 || !some_unknown) {
    status_share = json::object();
    for (std::size_t i = 0; i < status_cycles.size(); ++i) {
      const std::string name(core::to_string(static_cast<core::PlanStatus>(i)));
      status_share[name] = known_cycles > 0 ? status_cycles[i] / known_cycles : 0.0;
    }
    // Earlier rows without statuses: their cycles are normal ones.
    status_share["normal"] = known_cycles > 0 ? 1.0 - status_share["least_bad"].get<double>() -
                                                    status_share["fallback"].get<double>()
                                              : 0.0;
  }

  const Interval speed_ci = bootstrap_ratio(speed_num, speed_den, bootstrap_for("speed|" + key));
  const Interval incidents_ci = rate_interval(total_incidents, miles, 100.0);
  const double collisions = counts[static_cast<std::size_t>(sim::IncidentType::collision)];

  json row = {
      {"policy", policy},
      {"traffic", traffic},
      {"runs", n},
      {"total_miles", miles},
      {"mean_speed_mph", value(Metric::mean_speed_mph, mine)},
      {"mean_speed_mph_ci", pair_of(speed_ci)},
      {"incidents", total_incidents},
      {"incidents_per_100mi", miles > 0 ? 100.0 * total_incidents / miles : 0.0},
      {"incidents_per_100mi_ci", pair_of(incidents_ci)},
      {"incidents_per_100mi_by_type", per100},
      {"incidents_per_100mi_by_type_ci", per100_ci},
      {"incident_free_miles_median", median(free_miles)},
      {"incident_free_miles_median_ci",
       pair_of(bootstrap_median(free_miles, bootstrap_for("free|" + key)))},
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
        {"planner_wall_p99_us_worst", worst_wall_p99}}}};

  // Collisions: all of them, and (rows that classify them) at fault and by kind.
  const bool classified = available(Metric::at_fault_collisions_per_100mi, mine);
  json coll = {{"total", collisions},
               {"per_100mi", miles > 0 ? 100.0 * collisions / miles : 0.0},
               {"per_100mi_ci", pair_of(rate_interval(collisions, miles, 100.0))},
               {"at_fault", nullptr},
               {"at_fault_per_100mi", nullptr},
               {"at_fault_per_100mi_ci", nullptr},
               {"by_kind", nullptr}};
  Interval at_fault_ci;
  if (classified) {
    double at_fault = 0.0;
    std::array<double, sim::kCollisionKindCount> by_kind{};
    for (const RunRow* r : mine) {
      at_fault += r->at_fault_collisions;
      for (std::size_t k = 0; k < by_kind.size(); ++k) by_kind[k] += r->collisions_by_kind[k];
    }
    json kinds = json::object();
    for (std::size_t k = 0; k < by_kind.size(); ++k) kinds[kind_name(k)] = by_kind[k];
    at_fault_ci = rate_interval(at_fault, miles, 100.0);
    coll["at_fault"] = at_fault;
    coll["at_fault_per_100mi"] = miles > 0 ? 100.0 * at_fault / miles : 0.0;
    coll["at_fault_per_100mi_ci"] = pair_of(at_fault_ci);
    coll["by_kind"] = kinds;
  }
  row["collisions"] = coll;

  // Near misses (rows that measure them).
  if (available(Metric::near_misses_per_100mi, mine)) {
    double episodes = 0.0, ttc_below = 0.0, headway_below = 0.0;
    double ttc_ahead = kInf, ttc_entering = kInf, headway = kInf;
    for (const RunRow* r : mine) {
      episodes += r->near_misses;
      ttc_below += r->ttc_below_s;
      headway_below += r->headway_below_s;
      ttc_ahead = std::min(ttc_ahead, r->min_ttc_ahead_s);
      ttc_entering = std::min(ttc_entering, r->min_ttc_entering_s);
      headway = std::min(headway, r->min_headway_s);
    }
    row["near_misses"] = {{"episodes", episodes},
                          {"per_100mi", miles > 0 ? 100.0 * episodes / miles : 0.0},
                          {"per_100mi_ci", pair_of(rate_interval(episodes, miles, 100.0))},
                          {"min_ttc_ahead_s", finite_or_null(ttc_ahead)},
                          {"min_ttc_entering_s", finite_or_null(ttc_entering)},
                          {"min_time_headway_s", finite_or_null(headway)},
                          {"share_ttc_below", seconds > 0 ? ttc_below / seconds : 0.0},
                          {"share_headway_below", seconds > 0 ? headway_below / seconds : 0.0},
                          {"ttc_threshold_s", mine.front()->ttc_threshold_s},
                          {"headway_threshold_s", mine.front()->headway_threshold_s}};
  } else {
    row["near_misses"] = nullptr;
  }

  // How wide each interval is, and how many seeds would halve it.
  json prec = {
      {"mean_speed_mph", precision(speed_ci, seeds_to_halve_bootstrap(n))},
      {"incidents_per_100mi", precision(incidents_ci, seeds_to_halve_rate(total_incidents, n))},
      {"at_fault_collisions_per_100mi", nullptr}};
  if (classified) {
    prec["at_fault_collisions_per_100mi"] =
        precision(at_fault_ci, seeds_to_halve_rate(coll["at_fault"].get<double>(), n));
  }
  row["precision"] = prec;
  return row;
}

std::string verdict(const Interval& ci, bool higher_is_better) {
  if (!ci.excludes_zero()) return "no difference";
  const bool up = ci.lo > 0.0;
  return up == higher_is_better ? "better" : "worse";
}

}  // namespace

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  std::string s = buf;
  // No "-0.00": a value that rounds to zero is zero.
  if (s.front() == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

std::string signed_fixed(double v, int decimals) {
  std::string s = fixed(v, decimals);
  if (s.front() != '-') s.insert(0, "+");
  return s;
}

json summarize(const std::vector<RunRow>& runs, const std::vector<std::string>& policies,
               const std::vector<std::string>& traffic) {
  json rows = json::array();
  for (const auto& [p, t] : groups_of(runs, policies, traffic)) {
    std::vector<const RunRow*> mine;
    for (const RunRow& r : runs) {
      if (r.policy == p && r.traffic == t) mine.push_back(&r);
    }
    rows.push_back(summary_row(p, t, mine));
  }
  return rows;
}

json compare_paired(const std::vector<const RunRow*>& base,
                    const std::vector<const RunRow*>& candidate, std::string_view key,
                    const std::vector<Metric>& metrics) {
  // Pairs by seed, in the candidate's order.
  std::map<std::uint64_t, const RunRow*> by_seed;
  for (const RunRow* r : base) by_seed.emplace(r->seed, r);
  std::vector<const RunRow*> a, b;  // a: candidate, b: base
  for (const RunRow* r : candidate) {
    const auto it = by_seed.find(r->seed);
    if (it == by_seed.end()) continue;
    a.push_back(r);
    b.push_back(it->second);
  }
  json figures = json::object();
  for (const Metric m : metrics) {
    const MetricInfo& mi = info(m);
    if (a.empty() || !available(m, a) || !available(m, b)) {
      figures[std::string(mi.name)] = nullptr;
      continue;
    }
    std::vector<double> na, da, nb, db, va, vb;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const MetricTerms ta = terms(m, *a[i]);
      const MetricTerms tb = terms(m, *b[i]);
      na.push_back(ta.numerator);
      da.push_back(ta.denominator);
      nb.push_back(tb.numerator);
      db.push_back(tb.denominator);
      va.push_back(value(m, *a[i]));
      vb.push_back(value(m, *b[i]));
    }
    BootstrapOptions o;
    o.seed = bootstrap_seed(std::string(key) + "|" + std::string(mi.name));
    const Interval ci = bootstrap_ratio_difference(na, da, nb, db, o);
    const double cand = value(m, a);
    const double base_value = value(m, b);
    figures[std::string(mi.name)] = {
        {"candidate", cand},
        {"base", base_value},
        {"difference", cand - base_value},
        {"ci", pair_of(ci)},
        {"probability_of_improvement", probability_of_improvement(va, vb, mi.higher_is_better)},
        {"verdict", verdict(ci, mi.higher_is_better)}};
  }
  return {{"seeds", a.size()}, {"figures", figures}};
}

json pair_policies(const std::vector<RunRow>& runs, const std::vector<std::string>& policies,
                   const std::vector<std::string>& traffic) {
  std::vector<Metric> metrics(all_metrics().begin(), all_metrics().end());
  json pairs = json::array();
  for (const auto& t : traffic) {
    for (std::size_t i = 0; i < policies.size(); ++i) {
      for (std::size_t j = i + 1; j < policies.size(); ++j) {
        std::vector<const RunRow*> a, b;
        for (const RunRow& r : runs) {
          if (r.traffic != t) continue;
          if (r.policy == policies[i]) a.push_back(&r);
          if (r.policy == policies[j]) b.push_back(&r);
        }
        if (a.empty() || b.empty()) continue;
        json c = compare_paired(b, a, "pair|" + t + "|" + policies[i] + "|" + policies[j], metrics);
        if (c["seeds"].get<std::size_t>() == 0) continue;
        pairs.push_back({{"traffic", t},
                         {"policy", policies[i]},
                         {"versus", policies[j]},
                         {"seeds", c["seeds"]},
                         {"figures", c["figures"]}});
      }
    }
  }
  return pairs;
}

namespace {

std::string join_csv(const std::vector<std::string>& fields) {
  std::string line;
  for (const auto& f : fields) {
    if (!line.empty()) line += ',';
    line += f;
  }
  return line + "\n";
}

/// A number for CSV: empty for null.
std::string csv_number(const json& v, int decimals) {
  return v.is_number() ? fixed(v.get<double>(), decimals) : std::string();
}

/// "x (lo-hi)" for a value with an interval of non-negative values.
std::string with_ci(const json& v, const json& ci, int decimals) {
  if (!v.is_number()) return "–";
  std::string s = fixed(v.get<double>(), decimals);
  if (ci.is_array()) {
    s += " (" + fixed(ci[0].get<double>(), decimals) + "–" + fixed(ci[1].get<double>(), decimals) +
         ")";
  }
  return s;
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

/// A paired difference: "+0.27 (+0.05, +0.49) better" (the verdict only when beyond noise).
std::string difference_cell(const json& f, int decimals) {
  if (f.is_null()) return "–";
  std::string s = signed_fixed(f["difference"].get<double>(), decimals) + " (" +
                  signed_fixed(f["ci"][0].get<double>(), decimals) + ", " +
                  signed_fixed(f["ci"][1].get<double>(), decimals) + ")";
  const std::string v = f["verdict"].get<std::string>();
  if (v != "no difference") s += " **" + v + "**";
  return s;
}

std::string chance_cell(const json& f) {
  return f.is_null() ? "–" : fixed(f["probability_of_improvement"].get<double>(), 2);
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
    const json null = nullptr;
    const auto ci = [&](const json& pair, int i) { return pair.is_array() ? pair[i] : null; };
    const auto near = [&](const char* k) { return nm.is_null() ? null : nm[k]; };
    f.push_back(csv_number(r["mean_speed_mph_ci"][0], 3));
    f.push_back(csv_number(r["mean_speed_mph_ci"][1], 3));
    f.push_back(csv_number(r["incidents_per_100mi_ci"][0], 3));
    f.push_back(csv_number(r["incidents_per_100mi_ci"][1], 3));
    f.push_back(csv_number(c["per_100mi_ci"][0], 3));
    f.push_back(csv_number(c["per_100mi_ci"][1], 3));
    f.push_back(csv_number(c["at_fault"], 0));
    f.push_back(csv_number(c["at_fault_per_100mi"], 3));
    f.push_back(csv_number(ci(c["at_fault_per_100mi_ci"], 0), 3));
    f.push_back(csv_number(ci(c["at_fault_per_100mi_ci"], 1), 3));
    f.push_back(csv_number(r["incident_free_miles_median_ci"][0], 3));
    f.push_back(csv_number(r["incident_free_miles_median_ci"][1], 3));
    f.push_back(csv_number(near("episodes"), 0));
    f.push_back(csv_number(near("per_100mi"), 3));
    f.push_back(csv_number(ci(near("per_100mi_ci"), 0), 3));
    f.push_back(csv_number(ci(near("per_100mi_ci"), 1), 3));
    f.push_back(csv_number(near("min_ttc_ahead_s"), 3));
    f.push_back(csv_number(near("min_ttc_entering_s"), 3));
    f.push_back(csv_number(near("min_time_headway_s"), 3));
    f.push_back(csv_number(near("share_ttc_below"), 5));
    f.push_back(csv_number(near("share_headway_below"), 5));
    const json& prec = r["precision"];
    f.push_back(std::to_string(prec["mean_speed_mph"]["seeds_to_halve"].get<std::size_t>()));
    f.push_back(std::to_string(prec["incidents_per_100mi"]["seeds_to_halve"].get<std::size_t>()));
    f.push_back(
        prec["at_fault_collisions_per_100mi"].is_null()
            ? std::string()
            : std::to_string(
                  prec["at_fault_collisions_per_100mi"]["seeds_to_halve"].get<std::size_t>()));
    for (std::size_t k = 0; k < sim::kCollisionKindCount; ++k) {
      f.push_back(c["by_kind"].is_null() ? std::string()
                                         : csv_number(c["by_kind"][kind_name(k)], 0));
    }
    out += join_csv(f);
  }
  return out;
}

std::string pairs_csv(const json& pairs) {
  std::vector<std::string> header{"traffic", "policy", "versus", "seeds"};
  for (const Metric m : all_metrics()) {
    const std::string n(info(m).name);
    for (const char* suffix :
         {"_difference", "_lo", "_hi", "_probability_of_improvement", "_verdict"}) {
      header.push_back(n + suffix);
    }
  }
  std::string out = join_csv(header);
  for (const json& p : pairs) {
    std::vector<std::string> f{p["traffic"].get<std::string>(), p["policy"].get<std::string>(),
                               p["versus"].get<std::string>(),
                               std::to_string(p["seeds"].get<std::size_t>())};
    for (const Metric m : all_metrics()) {
      const json& fig = p["figures"][std::string(info(m).name)];
      if (fig.is_null()) {
        for (int k = 0; k < 5; ++k) f.emplace_back();
        continue;
      }
      f.push_back(fixed(fig["difference"], 4));
      f.push_back(fixed(fig["ci"][0], 4));
      f.push_back(fixed(fig["ci"][1], 4));
      f.push_back(fixed(fig["probability_of_improvement"], 3));
      f.push_back(fig["verdict"].get<std::string>());
    }
    out += join_csv(f);
  }
  return out;
}

std::string summary_markdown(const json& rows, const json& pairs) {
  std::string out;
  const auto head = [&](const std::string& p, const std::string& t) {
    return "| " + p + " | " + t + " | ";
  };
  out +=
      "Speed and incidents (95% intervals: bootstrap over runs for speed and incident-free "
      "miles, exact Poisson for the rates)\n\n"
      "| policy | traffic | runs | miles | mean mph | incidents /100 mi | collisions /100 mi | "
      "at fault /100 mi | speeding | max acc | max jerk | outside lane | incident-free mi, "
      "median / worst |\n"
      "|---|---|---:|---:|---|---|---|---|---:|---:|---:|---:|---|\n";
  for (const json& r : rows) {
    const json& by = r["incidents_per_100mi_by_type"];
    const json& c = r["collisions"];
    out += head(r["policy"], r["traffic"]) + std::to_string(r["runs"].get<std::size_t>()) + " | " +
           fixed(r["total_miles"], 1) + " | " +
           with_ci(r["mean_speed_mph"], r["mean_speed_mph_ci"], 2) + " | " +
           with_ci(r["incidents_per_100mi"], r["incidents_per_100mi_ci"], 2) + " | " +
           with_ci(c["per_100mi"], c["per_100mi_ci"], 2) + " | " +
           with_ci(c["at_fault_per_100mi"], c["at_fault_per_100mi_ci"], 2);
    for (const char* type : {"speeding", "max_acceleration", "max_jerk", "outside_lane"}) {
      out += " | " + fixed(by[type], 1);
    }
    out += " | " + with_ci(r["incident_free_miles_median"], r["incident_free_miles_median_ci"], 2) +
           " / " + fixed(r["incident_free_miles_worst"], 2) + " |\n";
  }

  const json* any_near = nullptr;
  for (const json& r : rows) {
    if (!r["near_misses"].is_null()) any_near = &r["near_misses"];
  }
  if (any_near) {
    const std::string ttc = fixed((*any_near)["ttc_threshold_s"], 1);
    const std::string hw = fixed((*any_near)["headway_threshold_s"], 1);
    out += "\nNear misses (least over the runs; shares of the time; an episode: TTC below " + ttc +
           " s without a contact)\n\n"
           "| policy | traffic | least TTC ahead (s) | least TTC entering a lane (s) | least "
           "headway (s) | time TTC < " +
           ttc + " s | time headway < " + hw +
           " s | near misses /100 mi |\n"
           "|---|---|---:|---:|---:|---:|---:|---|\n";
    for (const json& r : rows) {
      const json& nm = r["near_misses"];
      if (nm.is_null()) continue;
      out += head(r["policy"], r["traffic"]) + seconds_or_dash(nm["min_ttc_ahead_s"]) + " | " +
             seconds_or_dash(nm["min_ttc_entering_s"]) + " | " +
             seconds_or_dash(nm["min_time_headway_s"]) + " | " + percent(nm["share_ttc_below"], 2) +
             " | " + percent(nm["share_headway_below"], 1) + " | " +
             with_ci(nm["per_100mi"], nm["per_100mi_ci"], 2) + " |\n";
    }
  }

  bool classified = false;
  for (const json& r : rows) classified = classified || !r["collisions"]["by_kind"].is_null();
  if (classified) {
    out +=
        "\nCollisions by kind (whose fault: docs/evaluation.md)\n\n| policy | traffic | "
        "collisions | at fault |";
    for (std::size_t k = 0; k < sim::kCollisionKindCount; ++k) out += " " + kind_name(k) + " |";
    out += "\n|---|---|---:|---:|";
    for (std::size_t k = 0; k < sim::kCollisionKindCount; ++k) out += "---:|";
    out += "\n";
    for (const json& r : rows) {
      const json& c = r["collisions"];
      if (c["by_kind"].is_null()) continue;
      out += head(r["policy"], r["traffic"]) + fixed(c["total"], 0) + " | " +
             fixed(c["at_fault"], 0) + " |";
      for (std::size_t k = 0; k < sim::kCollisionKindCount; ++k) {
        out += " " + fixed(c["by_kind"][kind_name(k)], 0) + " |";
      }
      out += "\n";
    }
  }

  out +=
      "\nComfort and the planner\n\n"
      "| policy | traffic | peak acc / jerk (rubric) | peak acc / jerk (strict) | planner CPU us "
      "(p50 / p99) | cycles least-bad / fallback | ended early |\n"
      "|---|---|---|---|---|---|---:|\n";
  for (const json& r : rows) {
    out += head(r["policy"], r["traffic"]) + fixed(r["peak_acceleration_mps2"], 1) + " / " +
           fixed(r["peak_jerk_mps3"], 1) + " | " + fixed(r["peak_strict_acceleration_mps2"], 1) +
           " / " + fixed(r["peak_strict_jerk_mps3"], 1) + " | " +
           fixed(r["timing"]["planner_p50_us_median"], 0) + " / " +
           fixed(r["timing"]["planner_p99_us_worst"], 0) + " | " +
           status_cells(r["plan_status_share"]) + " | " +
           std::to_string(r["runs_ended_early"].get<std::size_t>()) + " |\n";
  }

  if (!pairs.empty()) {
    out +=
        "\nPaired comparisons (the same seeds; A - B with its 95% bootstrap interval over the "
        "seeds, **better** or **worse** when the interval excludes 0; P: the share of seeds on "
        "which A did better, ties half)\n\n"
        "| traffic | A vs B | seeds | mean mph | P | incidents /100 mi | P | at fault /100 mi | P "
        "|\n|---|---|---:|---|---:|---|---:|---|---:|\n";
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

  out +=
      "\nHow many seeds (± half the 95% interval; the seeds that would halve it, if the figures "
      "stay as they are)\n\n"
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
    out += head(r["policy"], r["traffic"]) + std::to_string(r["runs"].get<std::size_t>()) + " | " +
           cells(p["mean_speed_mph"], 2) + " | " + cells(p["incidents_per_100mi"], 2) + " | " +
           cells(p["at_fault_collisions_per_100mi"], 2) + " |\n";
  }
  return out;
}

}  // namespace overtake::eval
