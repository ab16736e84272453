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

BootstrapOptions bootstrap_for(const std::string& key, int resamples = kBootstrapResamples) {
  BootstrapOptions o;
  o.seed = bootstrap_seed(key);
  o.resamples = resamples;
  return o;
}

/// "too few seeds: 3, need at least 8", or "" when there are enough.
std::string too_few(std::size_t seeds) {
  if (seeds >= kMinSeeds) return {};
  return "too few seeds: " + std::to_string(seeds) + ", need at least " + std::to_string(kMinSeeds);
}

/// An interval as JSON, or null when there are too few seeds for one.
json ci_or_null(const Interval& i, bool enough) {
  return enough ? pair_of(i) : json(nullptr);
}

/// An interval's precision: its half width and the seeds that would halve it.
json precision(const Interval& i, std::size_t seeds_to_halve) {
  return {{"half_width", 0.5 * i.width()}, {"seeds_to_halve", seeds_to_halve}};
}

/// Events and miles of each run (one run per seed).
struct RateColumns {
  std::vector<double> events;
  std::vector<double> miles;
};

/// A rate per 100 miles with its interval over the runs: the figure, its interval (null with
/// too few seeds), a warning when one seed holds most of the events.
struct RateFigure {
  double value = 0.0;
  RateInterval interval;
  json ci = nullptr;
  std::size_t seeds_to_halve = 0;
};

RateFigure rate_figure(const RateColumns& c, bool enough) {
  RateFigure f;
  double k = 0.0, m = 0.0;
  for (std::size_t i = 0; i < c.events.size(); ++i) {
    k += c.events[i];
    m += c.miles[i];
  }
  f.value = m > 0 ? 100.0 * k / m : 0.0;
  f.interval = rate_interval(c.events, c.miles, 100.0);
  f.ci = ci_or_null(f.interval.ci, enough);
  f.seeds_to_halve = seeds_to_halve_rate(c.events, c.miles);
  return f;
}

/// A seed holding this share of a rate's events (or more), in a burst of at least so many,
/// makes its interval that seed's.
constexpr double kTopSeedWarning = 1.0 / 3.0;
constexpr double kBurstEvents = 3.0;

void warn_top_seed(json& warnings, const std::string& figure, const RateFigure& f,
                   std::size_t seeds) {
  const RateInterval& i = f.interval;
  if (seeds >= kMinSeeds && i.top_seed_share >= kTopSeedWarning &&
      i.top_seed_events >= kBurstEvents) {
    warnings.push_back(figure + ": one seed holds " + fixed(100.0 * i.top_seed_share, 0) +
                       "% of the events (" + fixed(i.top_seed_events, 0) +
                       "); the interval cannot tell how rare such bursts are");
  }
}

// What a group's rows add up to, besides the collisions and near misses.
struct RowTotals {
  double miles = 0.0, seconds = 0.0, peak_acc = 0.0, peak_jerk = 0.0, strict_acc = 0.0,
         strict_jerk = 0.0, worst_p99 = 0.0, worst_wall_p99 = 0.0, known_cycles = 0.0;
  std::vector<double> free_miles, p50s, speed_num, speed_den;
  std::array<RateColumns, sim::kIncidentTypeCount> by_type;
  RateColumns all_incidents;
  std::array<double, sim::kIncidentTypeCount> counts{};
  std::array<double, core::kPlanStatusCount> status_cycles{};
  bool some_unknown = false;  // a row, or some cycles of one, whose plan status is unknown
  std::size_t ended_early = 0;
  std::array<double, 2> declined{};  // lane changes declined, for cost and for safety
  bool declined_known = true;        // every row says how many
};

RowTotals totals_of(const std::vector<const RunRow*>& mine);

// Lane changes declined per 100 miles over the group, for cost and for safety: null unless
// every run says (a planner over the protocol does not).
json declined_per_100mi(const RowTotals& t) {
  if (!t.declined_known || !(t.miles > 0.0)) return nullptr;
  return {{"for_cost", 100.0 * t.declined[0] / t.miles},
          {"for_safety", 100.0 * t.declined[1] / t.miles}};
}

RowTotals totals_of(const std::vector<const RunRow*>& mine) {
  RowTotals t;
  for (const RunRow* r : mine) {
    t.miles += r->miles;
    t.seconds += r->seconds;
    t.free_miles.push_back(r->best_incident_free_miles);
    for (std::size_t k = 0; k < t.counts.size(); ++k) {
      t.counts[k] += r->incidents_by_type[k];
      t.by_type[k].events.push_back(r->incidents_by_type[k]);
      t.by_type[k].miles.push_back(r->miles);
    }
    t.all_incidents.events.push_back(r->incidents);
    t.all_incidents.miles.push_back(r->miles);
    t.peak_acc = std::max(t.peak_acc, r->peak_acceleration_mps2);
    t.peak_jerk = std::max(t.peak_jerk, r->peak_jerk_mps3);
    t.strict_acc = std::max(t.strict_acc, r->peak_strict_acceleration_mps2);
    t.strict_jerk = std::max(t.strict_jerk, r->peak_strict_jerk_mps3);
    t.p50s.push_back(r->planner_p50_us);
    t.worst_p99 = std::max(t.worst_p99, r->planner_p99_us);
    t.worst_wall_p99 = std::max(t.worst_wall_p99, r->planner_wall_p99_us);
    t.some_unknown = t.some_unknown || r->plan_status_unknown_cycles > 0 || !r->plan_status_known;
    if (r->plan_status_known) {
      t.known_cycles += r->planner_cycles - r->plan_status_unknown_cycles;
      for (std::size_t i = 0; i < t.status_cycles.size(); ++i)
        t.status_cycles[i] += r->plan_status_cycles[i];
    }
    if (r->ended_early) ++t.ended_early;
    if (r->changes_declined) {
      t.declined[0] += (*r->changes_declined)[0];
      t.declined[1] += (*r->changes_declined)[1];
    } else {
      t.declined_known = false;
    }
    const MetricTerms speed = terms(Metric::mean_speed_mph, *r);
    t.speed_num.push_back(speed.numerator);
    t.speed_den.push_back(speed.denominator);
  }
  return t;
}

// The shares of the cycles whose status is known. Null when none is but some cycles are
// unknown (a planner over the protocol does not say how it planned: its cycles are not
// normal ones). A group that mixes both (it should not: one planner per policy) gets the
// shares of the runs that say; those that do not are left out, not counted as normal.
json plan_status_share(const RowTotals& t) {
  if (!(t.known_cycles > 0 || !t.some_unknown)) return nullptr;
  json share = json::object();
  for (std::size_t i = 0; i < t.status_cycles.size(); ++i) {
    const std::string name(core::to_string(static_cast<core::PlanStatus>(i)));
    share[name] = t.known_cycles > 0 ? t.status_cycles[i] / t.known_cycles : 0.0;
  }
  // Earlier rows without statuses: their cycles are normal ones.
  share["normal"] = t.known_cycles > 0
                        ? 1.0 - share["least_bad"].get<double>() - share["fallback"].get<double>()
                        : 0.0;
  return share;
}

// Collisions as contacts (rows that count them so): all of them, at fault and by kind; and
// the rubric's collision incidents (one per second of contact) beside them. Null for rows
// that do not count them; `at_fault` is set when they do.
json collisions_part(const std::vector<const RunRow*>& mine, const RowTotals& t, bool enough,
                     json& warnings, std::optional<RateFigure>& at_fault) {
  if (!available(Metric::collisions_per_100mi, mine)) return nullptr;
  RateColumns all, mine_fault;
  std::array<double, sim::kCollisionKindCount> kinds{};
  double total = 0.0, fault = 0.0;
  for (const RunRow* r : mine) {
    all.events.push_back(r->collisions);
    all.miles.push_back(r->miles);
    mine_fault.events.push_back(r->at_fault_collisions);
    mine_fault.miles.push_back(r->miles);
    total += r->collisions;
    fault += r->at_fault_collisions;
    for (std::size_t k = 0; k < kinds.size(); ++k) kinds[k] += r->collisions_by_kind[k];
  }
  const RateFigure every = rate_figure(all, enough);
  at_fault = rate_figure(mine_fault, enough);
  warn_top_seed(warnings, "collisions_per_100mi", every, mine.size());
  warn_top_seed(warnings, "at_fault_collisions_per_100mi", *at_fault, mine.size());
  json by_kind = json::object();
  for (std::size_t k = 0; k < kinds.size(); ++k) by_kind[kind_name(k)] = kinds[k];
  const double rubric = t.counts[static_cast<std::size_t>(sim::IncidentType::collision)];
  return {{"total", total},
          {"per_100mi", every.value},
          {"per_100mi_ci", every.ci},
          {"at_fault", fault},
          {"at_fault_per_100mi", at_fault->value},
          {"at_fault_per_100mi_ci", at_fault->ci},
          {"by_kind", by_kind},
          {"rubric_incidents", rubric},
          {"rubric_per_100mi", t.miles > 0 ? 100.0 * rubric / t.miles : 0.0}};
}

// Near misses (rows that measure them; null for the others).
json near_misses_part(const std::vector<const RunRow*>& mine, const RowTotals& t, bool enough) {
  if (!available(Metric::near_misses_per_100mi, mine)) return nullptr;
  RateColumns episodes;
  double ttc_below = 0.0, headway_below = 0.0;
  double ttc_ahead = kInf, ttc_entering = kInf, headway = kInf;
  for (const RunRow* r : mine) {
    episodes.events.push_back(r->near_misses);
    episodes.miles.push_back(r->miles);
    ttc_below += r->ttc_below_s;
    headway_below += r->headway_below_s;
    ttc_ahead = std::min(ttc_ahead, r->min_ttc_ahead_s);
    ttc_entering = std::min(ttc_entering, r->min_ttc_entering_s);
    headway = std::min(headway, r->min_headway_s);
  }
  const RateFigure near = rate_figure(episodes, enough);
  double total = 0.0;
  for (const double e : episodes.events) total += e;
  return {{"episodes", total},
          {"per_100mi", near.value},
          {"per_100mi_ci", near.ci},
          {"min_ttc_ahead_s", finite_or_null(ttc_ahead)},
          {"min_ttc_entering_s", finite_or_null(ttc_entering)},
          {"min_time_headway_s", finite_or_null(headway)},
          {"share_ttc_below", t.seconds > 0 ? ttc_below / t.seconds : 0.0},
          {"share_headway_below", t.seconds > 0 ? headway_below / t.seconds : 0.0},
          {"ttc_threshold_s", mine.front()->ttc_threshold_s},
          {"headway_threshold_s", mine.front()->headway_threshold_s}};
}

json summary_row(const std::string& policy, const std::string& traffic,
                 const std::vector<const RunRow*>& mine) {
  const std::string key = policy + "|" + traffic;
  const RowTotals t = totals_of(mine);
  const std::size_t n = mine.size();
  const bool enough = n >= kMinSeeds;
  json warnings = json::array();
  double total_incidents = 0.0;
  json per100 = json::object(), per100_ci = json::object();
  for (std::size_t k = 0; k < t.counts.size(); ++k) {
    const RateFigure f = rate_figure(t.by_type[k], enough);
    per100[incident_name(k)] = f.value;
    per100_ci[incident_name(k)] = f.ci;
    total_incidents += t.counts[k];
  }
  const Interval speed_ci = mean_interval(t.speed_num, t.speed_den, bootstrap_for("speed|" + key));
  const RateFigure incidents = rate_figure(t.all_incidents, enough);
  warn_top_seed(warnings, "incidents_per_100mi", incidents, n);
  const auto& free = t.free_miles;

  json row = {{"policy", policy},
              {"traffic", traffic},
              {"runs", n},
              {"total_miles", t.miles},
              {"intervals", enough ? json(nullptr) : json(too_few(n))},
              {"mean_speed_mph", value(Metric::mean_speed_mph, mine)},
              {"mean_speed_mph_ci", ci_or_null(speed_ci, enough)},
              {"incidents", total_incidents},
              {"incidents_per_100mi", incidents.value},
              {"incidents_per_100mi_ci", incidents.ci},
              {"incidents_per_100mi_by_type", per100},
              {"incidents_per_100mi_by_type_ci", per100_ci},
              {"incident_free_miles_median", median(free)},
              {"incident_free_miles_median_ci", ci_or_null(median_interval(free), enough)},
              {"incident_free_miles_worst", *std::min_element(free.begin(), free.end())},
              {"peak_acceleration_mps2", t.peak_acc},
              {"peak_jerk_mps3", t.peak_jerk},
              {"peak_strict_acceleration_mps2", t.strict_acc},
              {"peak_strict_jerk_mps3", t.strict_jerk},
              {"plan_status_share", plan_status_share(t)},
              {"lane_changes_declined_per_100mi", declined_per_100mi(t)},
              {"runs_ended_early", t.ended_early},
              {"timing",
               {{"planner_p50_us_median", median(t.p50s)},
                {"planner_p99_us_worst", t.worst_p99},
                {"planner_wall_p99_us_worst", t.worst_wall_p99}}}};
  std::optional<RateFigure> at_fault;
  row["collisions"] = collisions_part(mine, t, enough, warnings, at_fault);
  row["near_misses"] = near_misses_part(mine, t, enough);

  // How wide each interval is, and how many seeds would halve it (by the same methods).
  json prec = {{"mean_speed_mph", nullptr},
               {"incidents_per_100mi", nullptr},
               {"at_fault_collisions_per_100mi", nullptr}};
  if (enough) {
    prec["mean_speed_mph"] = precision(speed_ci, seeds_to_halve_mean(n));
    prec["incidents_per_100mi"] = precision(incidents.interval.ci, incidents.seeds_to_halve);
    if (at_fault) {
      prec["at_fault_collisions_per_100mi"] =
          precision(at_fault->interval.ci, at_fault->seeds_to_halve);
    }
  }
  row["precision"] = prec;
  row["warnings"] = warnings;
  return row;
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
                    const std::vector<Metric>& metrics, int resamples) {
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
  const std::size_t n = a.size();
  const bool enough = n >= kMinSeeds;
  json figures = json::object();
  for (const Metric m : metrics) {
    const MetricInfo& mi = info(m);
    const std::string name(mi.name);
    if (a.empty() || !available(m, a) || !available(m, b)) {
      figures[name] = nullptr;
      continue;
    }
    std::vector<double> na, da, nb, db, va, vb;
    for (std::size_t i = 0; i < n; ++i) {
      const MetricTerms ta = terms(m, *a[i]);
      const MetricTerms tb = terms(m, *b[i]);
      na.push_back(ta.numerator);
      da.push_back(ta.denominator);
      nb.push_back(tb.numerator);
      db.push_back(tb.denominator);
      va.push_back(value(m, *a[i]));
      vb.push_back(value(m, *b[i]));
    }
    const PairedRatios pairs{na, da, nb, db};
    const std::string k = std::string(key) + "|" + name;
    const double cand = value(m, a);
    const double base_value = value(m, b);
    json f = {{"candidate", cand},
              {"base", base_value},
              {"difference", cand - base_value},
              {"ci", nullptr},
              {"p_value", nullptr},
              {"p_adjusted", nullptr},
              {"probability_of_improvement", nullptr},
              {"probability_of_improvement_ci", nullptr},
              {"verdict", "too few seeds"}};
    if (enough) {
      // Rates are numerators of 100 x events: their interval and test take the events.
      const bool mean = m == Metric::mean_speed_mph;
      std::vector<double> ea(na), eb(nb);
      for (double& e : ea) e /= 100.0;
      for (double& e : eb) e /= 100.0;
      const PairedRatios events{ea, da, eb, db};
      const Interval ci = mean
                              ? mean_difference_interval(pairs, bootstrap_for("ci|" + k, resamples))
                              : rate_difference_interval(events, 100.0);
      const Improvement imp = probability_of_improvement(va, vb, mi.higher_is_better,
                                                         bootstrap_for("p|" + k, resamples));
      f["ci"] = pair_of(ci);
      f["probability_of_improvement"] = imp.p;
      f["probability_of_improvement_ci"] = pair_of(imp.ci);
      // A figure that is the same on every seed (no event in either arm, say) has nothing to
      // test: "no difference", outside the family (a test that cannot reject would only make
      // the correction of the others stricter). Else the family's correction decides.
      bool differs = false;
      for (std::size_t i = 0; i < n; ++i) differs = differs || va[i] != vb[i];
      if (differs) {
        f["p_value"] = mean ? mean_difference_p_value(pairs)
                            : rate_difference_p_value(events, bootstrap_seed("flip|" + k));
        f["verdict"] = nullptr;  // judge_family
      } else {
        f["verdict"] = "no difference";
      }
    }
    figures[name] = f;
  }
  return {{"seeds", n}, {"figures", figures}};
}

std::size_t judge_family(json& comparisons) {
  std::vector<double> p;
  std::vector<std::pair<json*, const MetricInfo*>> tested;
  for (json& c : comparisons) {
    for (auto& [name, f] : c["figures"].items()) {
      const std::optional<Metric> m = parse_metric(name);
      if (!m || !f.is_object() || !f["p_value"].is_number()) continue;
      p.push_back(f["p_value"].get<double>());
      tested.emplace_back(&f, &info(*m));
    }
  }
  const std::vector<double> adjusted = holm_adjust(p);
  for (std::size_t i = 0; i < tested.size(); ++i) {
    json& f = *tested[i].first;
    f["p_adjusted"] = adjusted[i];
    std::string v = "no difference";
    if (adjusted[i] < kFamilyAlpha) {
      const double d = f["difference"].get<double>();
      v = (d > 0.0) == tested[i].second->higher_is_better ? "better" : "worse";
    }
    f["verdict"] = v;
  }
  return tested.size();
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
  judge_family(pairs);
  return pairs;
}

json verdict_method(std::size_t tests) {
  return {{"alpha", kFamilyAlpha},
          {"correction", "Holm"},
          {"family_tests", tests},
          {"min_seeds", kMinSeeds},
          {"mean_test", "paired t-test on the seeds' linearized differences"},
          {"rate_test", "exact sign-flip randomization test over seeds"},
          {"mean_interval",
           "bootstrap-t over seeds: the span of its symmetric and equal-tailed intervals"},
          {"rate_interval",
           "exact (Garwood) interval on the events over the seeds' dispersion "
           "(quasi-Poisson, t-scaled); no event: one-sided upper bound"},
          {"difference_interval",
           "means: paired bootstrap-t (the same span); rates: MOVER from both rates' intervals"}};
}

std::size_t family_size(const json& pairs) {
  std::size_t n = 0;
  for (const json& p : pairs) {
    for (const auto& [name, f] : p["figures"].items()) {
      if (f.is_object() && f["p_value"].is_number()) ++n;
    }
  }
  return n;
}

}  // namespace overtake::eval
