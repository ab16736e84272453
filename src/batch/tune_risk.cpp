// `overtake tune --max-risk`: each trial's rate of an event estimated by `overtake risk` on the
// same runs as every other trial's, pooled over the maps and traffic profiles of the search,
// and the start's and the best's estimates again on runs of their own for the validation.

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "overtake/base/errors.hpp"
#include "overtake/base/text.hpp"
#include "overtake/core/units.hpp"
#include "overtake/eval/splitting.hpp"
#include "tune_internal.hpp"

namespace overtake::batch {

using base::fixed_text;
using base::UsageError;
using nlohmann::json;
namespace fs = std::filesystem;

const std::vector<std::string>& tune_risk_figure_names() {
  static const std::vector<std::string> names = {"risk_per_100mi",      "risk_low_per_100mi",
                                                 "risk_high_per_100mi", "risk_events",
                                                 "risk_miles",          "risk_hours"};
  return names;
}

namespace tune_detail {
namespace {

constexpr double kPer100Mi = 100.0 * core::kMetresPerMile;  // a rate per metre, per 100 mi

bool is_risk_figure(const std::string& name) {
  const auto& n = tune_risk_figure_names();
  return std::find(n.begin(), n.end(), name) != n.end();
}

RiskSpec risk_spec_of(const TuneSpec& spec, const RiskPlanner& p, const MapChoice& map,
                      const std::string& traffic, std::uint64_t first_seed, double hours,
                      double rel_error, fs::path out) {
  RiskSpec r;
  r.policy = p.policy;
  r.planners = p.planners;
  r.config = p.config;
  r.map = map;
  r.traffic = traffic;
  r.first_seed = first_seed;
  r.minutes = spec.minutes;
  r.event = spec.risk->event;
  r.rel_error = rel_error;
  r.budget_hours = hours;
  r.jobs = spec.jobs;
  r.out = std::move(out);
  r.scenarios = 0;  // a search wants the rate; `overtake risk` on best.json cuts the events
  return r;
}

// The trials' risk runs, and where the validation's begin: past every run a trial's budget
// can reach, so the two never share a run.
std::size_t runs_planned(const TuneSpec& spec, double hours) {
  RiskSpec r;
  r.minutes = spec.minutes;
  r.budget_hours = hours;
  return risk_runs_planned(r);
}
std::uint64_t validation_first_seed(const TuneSpec& spec) {
  return spec.risk->first_seed + runs_planned(spec, spec.risk->hours);
}

// Where the estimate of map `k` of `maps` and traffic profile `traffic` goes under `dir`.
fs::path estimate_folder(const fs::path& dir, const TuneSpec& spec, std::size_t k,
                         const std::string& traffic) {
  const std::size_t maps = maps_of(spec).size();
  if (maps == 1 && spec.traffic.size() == 1) return dir;
  if (maps == 1) return dir / traffic;
  return dir / ("map-" + std::to_string(k + 1) + (spec.traffic.size() == 1 ? "" : "-" + traffic));
}

// The estimates of one planner on `maps` (each traffic profile), pooled.
struct Pooled {
  std::vector<double> weighted_events;
  std::vector<double> exposure_m;
  double simulated_h = 0.0;
  bool interrupted = false;

  void add(const RiskOutcome& o) {
    for (const RiskRun& r : o.runs) {
      weighted_events.push_back(r.tally.weighted_events);
      exposure_m.push_back(r.tally.exposure);
    }
    simulated_h += o.simulated_h;
    interrupted = interrupted || o.interrupted;
  }

  [[nodiscard]] eval::RateEstimate rate_per_100mi() const {
    const eval::SplitEstimate e = eval::split_estimate(weighted_events, exposure_m);
    return {e.rate * kPer100Mi, {e.ci.lo * kPer100Mi, e.ci.hi * kPer100Mi}, e.upper_bound_only};
  }

  [[nodiscard]] json figures() const {
    const eval::RateEstimate r = rate_per_100mi();
    double events = 0.0, metres = 0.0;
    for (const double y : weighted_events) events += y;
    for (const double m : exposure_m) metres += m;
    return {{"risk_per_100mi", r.rate},
            {"risk_low_per_100mi", r.ci.lo},
            {"risk_high_per_100mi", r.ci.hi},
            {"risk_events", events},
            {"risk_miles", metres / core::kMetresPerMile},
            {"risk_hours", simulated_h}};
  }
};

Pooled estimate(const TuneSpec& spec, const RiskPlanner& planner,
                const std::vector<std::pair<std::size_t, MapChoice>>& maps,
                std::uint64_t first_seed, double hours, double rel_error, const fs::path& dir,
                const std::atomic<bool>* stop) {
  Pooled pooled;
  for (const auto& [k, map] : maps) {
    for (const std::string& traffic : spec.traffic) {
      const RiskSpec r = risk_spec_of(spec, planner, map, traffic, first_seed, hours, rel_error,
                                      estimate_folder(dir, spec, k, traffic));
      pooled.add(run_risk(r, stop, nullptr));
      if (pooled.interrupted) return pooled;
    }
  }
  return pooled;
}

std::string rate_text(const json& e) {
  return fixed_text(e["rate_per_100mi"].get<double>(), 3) + " per 100 mi (95% interval " +
         fixed_text(e["ci95_per_100mi"][0].get<double>(), 3) + " to " +
         fixed_text(e["ci95_per_100mi"][1].get<double>(), 3) + ", " +
         fixed_text(e["miles"].get<double>(), 0) + " mi)";
}

json estimate_json(const Pooled& p) {
  const eval::RateEstimate r = p.rate_per_100mi();
  const json f = p.figures();
  return {{"rate_per_100mi", r.rate},
          {"ci95_per_100mi", {r.ci.lo, r.ci.hi}},
          {"upper_bound_only", r.upper_bound_only},
          {"events", f["risk_events"]},
          {"miles", f["risk_miles"]},
          {"simulated_h", f["risk_hours"]}};
}

}  // namespace

std::vector<TuneConstraint> constraints_of(const TuneSpec& spec) {
  std::vector<TuneConstraint> all = spec.constraints;
  if (spec.risk && spec.risk->max_per_100mi) {
    all.push_back({"risk_per_100mi", true, *spec.risk->max_per_100mi});
  }
  return all;
}

void check_tune_risk(const TuneSpec& spec) {
  if (!spec.risk) {
    std::vector<std::string> named = {spec.objective};
    for (const auto& c : spec.constraints) named.push_back(c.figure);
    for (const auto& n : named) {
      if (is_risk_figure(n)) {
        throw UsageError("'" + n +
                         "' is a figure of each trial's risk estimate: give --max-risk RATE or "
                         "--risk-hours H to estimate it");
      }
    }
    return;
  }
  const TuneRisk& r = *spec.risk;
  if (r.max_per_100mi && !(*r.max_per_100mi >= 0.0 && std::isfinite(*r.max_per_100mi))) {
    throw UsageError("--max-risk must be a rate per 100 mi of at least 0");
  }
  if (!(r.hours > 0.0 && r.hours <= 1e6)) {
    throw UsageError("--risk-hours must be more than 0 and at most 1000000");
  }
  if (!(r.validation_hours > 0.0 && r.validation_hours <= 1e6)) {
    throw UsageError("--risk-validation-hours must be more than 0 and at most 1000000");
  }
  if (!(r.rel_error >= 0.0 && r.rel_error < 10.0)) {
    throw UsageError("--risk-rel-error must be from 0 (none) to below 10");
  }
  if (spec.minutes < 1.0) {
    throw UsageError("--minutes: a trial's risk is estimated from runs of at least 1 min (got " +
                     fixed_text(spec.minutes, 2) + "); give --minutes 1 or more");
  }
  for (const std::string& traffic : spec.traffic) {
    check_risk_spec(risk_spec_of(spec, {spec.policy, spec.planners, spec.config}, std::nullopt,
                                 traffic, r.first_seed, r.hours, r.rel_error, spec.out / "trials"));
  }
  // The trials' runs must not be held-out ones, nor the validation's training ones.
  const std::uint64_t trials_end = validation_first_seed(spec);
  const std::uint64_t validation_end = trials_end + runs_planned(spec, r.validation_hours);
  const auto within = [](std::uint64_t s, std::uint64_t lo, std::uint64_t hi) {
    return s >= lo && s < hi;
  };
  const std::string ranges = "the trials' risk runs take seeds " + std::to_string(r.first_seed) +
                             "-" + std::to_string(trials_end - 1) + ", the validation's " +
                             std::to_string(trials_end) + "-" + std::to_string(validation_end - 1);
  for (const std::uint64_t s : spec.validation_seeds) {
    if (within(s, r.first_seed, trials_end)) {
      throw UsageError("--risk-first-seed: " + ranges + ", and " + std::to_string(s) +
                       " is a held-out seed; choose a --risk-first-seed past the seeds");
    }
  }
  if (!spec.validation_seeds.empty()) {
    for (const std::uint64_t s : spec.seeds) {
      if (within(s, trials_end, validation_end)) {
        throw UsageError("--risk-first-seed: " + ranges + ", and " + std::to_string(s) +
                         " is a training seed; choose a --risk-first-seed past the seeds");
      }
    }
  }
}

std::optional<json> trial_risk(const TuneSpec& spec, const RiskPlanner& planner,
                               const fs::path& dir, const std::atomic<bool>* stop) {
  std::vector<std::pair<std::size_t, MapChoice>> maps;
  const std::vector<MapChoice> all = maps_of(spec);
  for (std::size_t k = 0; k < all.size(); ++k) maps.emplace_back(k, all[k]);
  try {
    const Pooled p = estimate(spec, planner, maps, spec.risk->first_seed, spec.risk->hours,
                              spec.risk->rel_error, dir, stop);
    if (p.interrupted) return std::nullopt;
    return p.figures();
  } catch (const UsageError&) {
    throw;
  } catch (const std::runtime_error& e) {
    // The planner failed in a run (risk names the run and seed): not a rate, and not a
    // feasible trial, but the search goes on.
    json f = json::object();
    for (const auto& n : tune_risk_figure_names()) f[n] = nullptr;
    f["risk_error"] = e.what();
    return f;
  }
}

json validate_risk_on(const TuneSpec& spec, const RiskPlanner& start, const RiskPlanner& best,
                      const MapChoice& map, const fs::path& dir, const std::atomic<bool>* stop,
                      bool& interrupted) {
  const std::vector<std::pair<std::size_t, MapChoice>> one = {{0, map}};
  json v = {{"first_seed", validation_first_seed(spec)}, {"hours", spec.risk->validation_hours}};
  std::vector<eval::RateEstimate> rates;
  TuneSpec one_map = spec;
  one_map.maps = {map};
  for (const auto& [name, planner] : {std::pair{"start", &start}, std::pair{"best", &best}}) {
    // The full budget each (no early stop), on the same held-out runs.
    const Pooled p =
        estimate(one_map, *planner, one, validation_first_seed(spec), spec.risk->validation_hours,
                 0.0, dir / (std::string("risk-") + name), stop);
    if (p.interrupted) {
      interrupted = true;
      return nullptr;
    }
    v[name] = estimate_json(p);
    rates.push_back(p.rate_per_100mi());
  }
  const eval::RateRatio ratio = eval::rate_ratio(rates[0], rates[1]);
  v["ratio"] = {{"defined", ratio.defined},
                {"ratio", ratio.ratio},
                {"ci95", {ratio.ci.lo, std::isfinite(ratio.ci.hi) ? json(ratio.ci.hi) : json()}},
                {"verdict", ratio.verdict}};
  return v;
}

std::string risk_verdict_of(const TuneSpec& spec, const json& v) {
  if (v.is_null()) return "The risk was not validated.";
  const std::string event = spec.risk->event.name();
  const json& best = v["best"];
  std::string s = "On held-out runs the best's " + event + " rate is " + rate_text(best) +
                  ", the start's " + rate_text(v["start"]) + "";
  const std::string verdict = v["ratio"]["verdict"].get<std::string>();
  if (verdict == "higher") {
    s += ": the best's is higher";
  } else if (verdict == "lower") {
    s += ": the best's is lower";
  } else if (verdict == "no verdict") {
    s += ": no verdict (neither saw an event)";
  } else {
    s += ": no difference shown";
  }
  s += ".";
  if (const auto limit = spec.risk->max_per_100mi) {
    const double rate = best["rate_per_100mi"].get<double>();
    const double high = best["ci95_per_100mi"][1].get<double>();
    const std::string l = fixed_text(*limit, 3);
    if (high <= *limit) {
      s += " Within the limit of " + l + ": even the interval's upper end is.";
    } else if (rate <= *limit) {
      s += " Within the limit of " + l +
           " by its estimate, not shown to be: the interval's upper end is above it (more "
           "--risk-validation-hours narrow it).";
    } else {
      s += " ABOVE the limit of " + l +
           " on held-out runs: the trials' budget was too small "
           "to see it, or the best fits the trials' runs only.";
    }
  }
  return s;
}

}  // namespace tune_detail
}  // namespace overtake::batch
