// `overtake risk`: the estimate's loop (base runs in batches, each split), its stopping rules,
// the runs kept in --out for --resume, and what it reports.

#include "overtake/batch/risk.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

#include "overtake/base/build_info.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/pool.hpp"
#include "overtake/core/hash.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/resources.hpp"
#include "risk_internal.hpp"

namespace overtake::batch {

using base::UsageError;
using nlohmann::json;
using risk_detail::miles_of;
using risk_detail::RunInputs;
using run::ConfigError;

namespace {

constexpr double kPer100Mi = 100.0;
constexpr const char* kRunsFile = "runs.jsonl";
constexpr const char* kSpecFile = "risk-spec.json";

}  // namespace

std::string RiskEvent::name() const {
  switch (kind) {
    case RiskEventKind::at_fault:
      return "at-fault";
    case RiskEventKind::contact:
      return "contact";
    case RiskEventKind::near_miss:
      return "near-miss";
    case RiskEventKind::incident:
      return std::string(sim::to_string(incident));
  }
  return "?";
}

RiskEvent parse_risk_event(const std::string& name) {
  if (name == "at-fault") return {RiskEventKind::at_fault};
  if (name == "contact") return {RiskEventKind::contact};
  if (name == "near-miss") return {RiskEventKind::near_miss};
  std::string types;
  for (std::size_t t = 0; t < sim::kIncidentTypeCount; ++t) {
    const auto type = static_cast<sim::IncidentType>(t);
    if (name == sim::to_string(type)) return {RiskEventKind::incident, type};
    types += std::string(t ? ", " : "") + std::string(sim::to_string(type));
  }
  throw UsageError("--event: '" + name +
                   "' is none of at-fault, contact, near-miss or a rubric incident type (" + types +
                   ")");
}

// ---------------------------------------------------------------------------------------
// Parameters

eval::SplitLevels RiskParams::levels() const {
  eval::SplitLevels l;
  for (std::size_t j = 0; j < margins_m.size(); ++j) {
    l.thresholds.push_back(-margins_m[j]);
    l.splits.push_back(j < splits.size() ? splits[j] : 1);
  }
  return l;
}

void RiskParams::validate() const {
  const auto bad = [](const std::string& key, const std::string& why) {
    throw ConfigError("risk params: " + key + ": " + why);
  };
  if (margins_m.size() != splits.size()) {
    bad("splits", "one per margin (" + std::to_string(margins_m.size()) + " margins, " +
                      std::to_string(splits.size()) + " splits)");
  }
  if (margins_m.size() > 16) bad("margins_m", "at most 16 levels");
  for (std::size_t j = 0; j < margins_m.size(); ++j) {
    if (!std::isfinite(margins_m[j]) || margins_m[j] < -10.0 || margins_m[j] > 100.0)
      bad("margins_m", "each from -10 to 100 m");
    if (j > 0 && !(margins_m[j] < margins_m[j - 1])) bad("margins_m", "must decrease");
    if (splits[j] < 1 || splits[j] > 50) bad("splits", "each from 1 to 50");
  }
  const auto range = [&](const std::string& key, double v, double lo, double hi) {
    if (!std::isfinite(v) || v < lo || v > hi) {
      bad(key, "must be from " + base::fixed_text(lo, 1) + " to " + base::fixed_text(hi, 1));
    }
  };
  range("score.horizon_s", score.horizon_s, 0.0, 10.0);
  range("score.time_weight_mps", score.time_weight_mps, 0.0, 50.0);
  range("score.lateral_weight", score.lateral_weight, 0.1, 20.0);
  range("score.range_m", score.range_m, 10.0, 1000.0);
  if (max_paths < 1 || max_paths > 10'000'000) bad("max_paths", "must be from 1 to 10000000");
  if (batch_runs < 1 || batch_runs > 10000) bad("batch_runs", "must be from 1 to 10000");
  if (min_runs_with_events < 1) bad("min_runs_with_events", "must be at least 1");
}

namespace {

// Reads `j`'s keys into `p`, refusing unknown keys and wrong types (ConfigError naming
// `source` and the key).
void apply_risk_json(RiskParams& p, const json& j, const std::string& source) {
  const auto fail = [&](const std::string& key, const std::string& why) {
    throw ConfigError(source + ": " + key + ": " + why);
  };
  if (!j.is_object()) fail("(top)", "must be an object");
  const auto number = [&](const json& v, const std::string& key) {
    if (!v.is_number()) fail(key, "must be a number");
    return v.get<double>();
  };
  for (const auto& [key, v] : j.items()) {
    if (key == "score") {
      if (!v.is_object()) fail(key, "must be an object");
      for (const auto& [k, x] : v.items()) {
        const std::string name = "score." + k;
        if (k == "horizon_s") {
          p.score.horizon_s = number(x, name);
        } else if (k == "time_weight_mps") {
          p.score.time_weight_mps = number(x, name);
        } else if (k == "lateral_weight") {
          p.score.lateral_weight = number(x, name);
        } else if (k == "range_m") {
          p.score.range_m = number(x, name);
        } else {
          fail(name, "is not a key of the risk params");
        }
      }
    } else if (key == "margins_m" || key == "splits") {
      if (!v.is_array()) fail(key, "must be a list of numbers");
      std::vector<double> xs;
      for (const json& x : v) xs.push_back(number(x, key));
      if (key == "margins_m") {
        p.margins_m = xs;
      } else {
        p.splits.clear();
        for (double x : xs) {
          if (x != std::floor(x) || std::abs(x) > 1e6) fail(key, "must be whole numbers");
          p.splits.push_back(static_cast<int>(x));
        }
      }
    } else if (key == "max_paths" || key == "batch_runs" || key == "min_runs_with_events") {
      const double x = number(v, key);
      if (x != std::floor(x) || x < 0 || x > 1e9) fail(key, "must be a whole number");
      if (key == "max_paths") p.max_paths = static_cast<std::size_t>(x);
      if (key == "batch_runs") p.batch_runs = static_cast<int>(x);
      if (key == "min_runs_with_events") p.min_runs_with_events = static_cast<int>(x);
    } else if (key == "//" || key.starts_with("_")) {
      // comments
    } else {
      fail(key, "is not a key of the risk params");
    }
  }
  try {
    p.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(source + ": " +
                      std::string(e.what()).substr(std::string("risk params: ").size()));
  }
}

}  // namespace

RiskParams load_risk_params(const std::optional<std::filesystem::path>& path) {
  RiskParams p;
  const auto text = resources::embedded_file("config/risk.json");
  if (!text) throw ConfigError("built-in config/risk.json is missing from this build");
  apply_risk_json(p, run::parse_json_text(*text, "built-in config/risk.json"),
                  "built-in config/risk.json");
  if (path) apply_risk_json(p, run::read_json_file(*path), path->string());
  return p;
}

json risk_params_json(const RiskParams& p) {
  return {{"score",
           {{"horizon_s", p.score.horizon_s},
            {"time_weight_mps", p.score.time_weight_mps},
            {"lateral_weight", p.score.lateral_weight},
            {"range_m", p.score.range_m}}},
          {"margins_m", p.margins_m},
          {"splits", p.splits},
          {"max_paths", p.max_paths},
          {"batch_runs", p.batch_runs},
          {"min_runs_with_events", p.min_runs_with_events}};
}

// ---------------------------------------------------------------------------------------
// The spec and what identifies an estimate

void check_risk_spec(const RiskSpec& spec) {
  if (!(spec.minutes >= 1.0 && spec.minutes <= 1440.0))
    throw UsageError("--minutes must be from 1 to 1440 (got " + base::fixed_text(spec.minutes, 2) +
                     ")");
  if (!(spec.rel_error >= 0.0 && spec.rel_error < 10.0))
    throw UsageError("--rel-error must be from 0 (none) to below 10 (got " +
                     base::fixed_text(spec.rel_error, 3) + ")");
  if (!(spec.budget_hours > 0.0 && spec.budget_hours <= 1e6))
    throw UsageError("--budget-hours must be more than 0 and at most 1000000");
  if (spec.max_runs < 1) throw UsageError("--max-runs must be at least 1");
  check_jobs(spec.jobs);
  if (!sim::parse_traffic_profile(spec.traffic))
    throw UsageError("--traffic: '" + spec.traffic + "' is not a traffic profile");
  const planners::PlannerCatalog builtins;
  const planners::PlannerCatalog& catalog = spec.planners ? *spec.planners : builtins;
  const planners::PlannerEntry* entry = catalog.find(spec.policy);
  if (!entry) throw UsageError("--policy: '" + spec.policy + "' is not a planner this run knows");
  if (entry->kind != planners::PlannerKind::builtin) {
    const RiskParams params = load_risk_params(spec.params);
    const bool splits =
        std::any_of(params.splits.begin(), params.splits.end(), [](int r) { return r > 1; });
    if (splits) {
      throw UsageError(
          "--params: " + entry->label() +
          " is a planner from outside, and the levels split: a copy is made from a checkpoint "
          "of the world and of the planner's own state, which only a built-in policy gives (a "
          "planner from outside would need the warm-up at every copy, not built yet; "
          "docs/evaluation.md, \"Rare events\"). Without splits (the shipped levels) it is "
          "estimated from plain runs");
    }
  }
}

namespace {

// What makes the runs of --out one estimate: a resume of anything else is refused.
json identity_of(const RiskSpec& spec, const RunInputs& in, const RiskParams& params) {
  return {{"policy", spec.policy},
          {"planner", in.entry->describe()},
          {"event", spec.event.name()},
          {"map", in.track->map.source},
          {"map_hash", core::hex64(in.track->map.content_hash)},
          {"traffic", spec.traffic},
          {"minutes", spec.minutes},
          {"first_seed", spec.first_seed},
          {"config_hash", run::config_hash(in.config)},
          {"params", risk_params_json(params)},
          {"revision", std::string(base::build_revision())}};
}

json run_to_json(const RiskRun& r) {
  json events = json::array();
  for (const eval::SplitEvent& e : r.tally.events) {
    events.push_back({{"weight", e.weight},
                      {"level", e.level},
                      {"path", e.path},
                      {"t_s", e.at},
                      {"branch_t_s", e.base_cost}});
  }
  return {{"run", r.index},
          {"seed", r.seed},
          {"weighted_events", r.tally.weighted_events},
          {"base_events", r.tally.base_events},
          {"exposure_m", r.tally.exposure},
          {"cost_s", r.tally.cost},
          {"base_cost_s", r.tally.base_cost},
          {"paths", r.tally.paths},
          {"crossings", r.tally.crossings},
          {"events", events},
          {"wall_s", r.wall_s}};
}

RiskRun run_from_json(const json& j) {
  RiskRun r;
  r.index = j.at("run").get<std::size_t>();
  r.seed = j.at("seed").get<std::uint64_t>();
  r.tally.weighted_events = j.at("weighted_events").get<double>();
  r.tally.base_events = j.at("base_events").get<int>();
  r.tally.exposure = j.at("exposure_m").get<double>();
  r.tally.cost = j.at("cost_s").get<double>();
  r.tally.base_cost = j.at("base_cost_s").get<double>();
  r.tally.paths = j.at("paths").get<std::size_t>();
  r.tally.crossings = j.at("crossings").get<std::vector<double>>();
  for (const json& e : j.at("events")) {
    r.tally.events.push_back({e.at("weight").get<double>(), e.at("level").get<int>(),
                              e.at("path").get<std::size_t>(), e.at("branch_t_s").get<double>(),
                              e.at("t_s").get<double>()});
  }
  r.wall_s = j.at("wall_s").get<double>();
  return r;
}

// The runs kept in --out (resume), checked against this estimate's identity.
std::vector<RiskRun> read_kept_runs(const RiskSpec& spec, const json& identity) {
  const auto spec_file = spec.out / kSpecFile;
  const auto runs_file = spec.out / kRunsFile;
  const bool held = std::filesystem::exists(spec_file) || std::filesystem::exists(runs_file);
  if (!spec.resume) {
    if (held) {
      throw UsageError("--out: " + spec.out.string() +
                       " already holds an estimate; give --resume to go on with it, or choose "
                       "another --out");
    }
    return {};
  }
  if (!held) return {};
  json kept;
  try {
    kept = run::read_json_file(spec_file);
  } catch (const std::exception& e) {
    throw UsageError(std::string("--resume: ") + e.what());
  }
  for (const auto& [key, v] : identity.items()) {
    if (!kept.contains(key) || kept[key] != v) {
      throw UsageError("--resume: the estimate in " + spec.out.string() + " is of another " + key +
                       " (" + (kept.contains(key) ? kept[key].dump() : "none") + ", now " +
                       v.dump() + "); choose another --out");
    }
  }
  std::vector<RiskRun> runs;
  std::ifstream in(runs_file);
  std::string line;
  std::size_t n = 0;
  std::vector<std::string> lines;
  while (std::getline(in, line)) lines.push_back(line);
  for (const std::string& l : lines) {
    ++n;
    try {
      RiskRun r = run_from_json(json::parse(l));
      if (r.index != runs.size()) throw std::runtime_error("runs out of order");
      runs.push_back(std::move(r));
    } catch (const std::exception& e) {
      // A last line cut short by a crash is dropped (its run is done again); any other is an
      // error.
      if (n == lines.size()) break;
      throw UsageError("--resume: " + runs_file.string() + " line " + std::to_string(n) + ": " +
                       e.what());
    }
  }
  return runs;
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  base::write_file_atomic(path, text);
}

// The outcome's figures from its runs.
void sum_up(RiskOutcome& o) {
  std::vector<double> y, m;
  double cost = 0.0, base = 0.0;
  for (const RiskRun& r : o.runs) {
    y.push_back(r.tally.weighted_events);
    m.push_back(r.tally.exposure);
    cost += r.tally.cost;
    base += r.tally.base_cost;
  }
  o.estimate = eval::split_estimate(y, m);
  double metres = 0.0;
  for (double x : m) metres += x;
  o.miles = miles_of(metres);
  o.simulated_h = cost / 3600.0;
  o.base_h = base / 3600.0;
  if (o.estimate.upper_bound_only || o.estimate.variance <= 0.0 || base <= 0.0) {
    o.plain_mc_h = o.base_h;  // the same bound takes the same plain runs
  } else {
    // A plain estimate from M metres has the Poisson variance rate / M.
    const double metres_needed = o.estimate.rate / o.estimate.variance;
    o.plain_mc_h = metres_needed / (metres / o.base_h);
  }
  o.gain = o.simulated_h > 0.0 ? o.plain_mc_h / o.simulated_h : 0.0;
}

double rel_half_width(const eval::SplitEstimate& e) {
  if (e.upper_bound_only || e.rate <= 0.0) return 0.0;
  return 0.5 * (e.ci.hi - e.ci.lo) / e.rate;
}

RiskProgress progress_of(const RiskSpec& spec, const RiskOutcome& o, double wall_s) {
  RiskProgress p;
  p.runs = o.runs.size();
  p.simulated_h = o.simulated_h;
  p.budget_h = spec.budget_hours;
  for (const RiskRun& r : o.runs) p.weighted_events += r.tally.weighted_events;
  p.rate_per_100mi = o.estimate.rate * 1609.344 * kPer100Mi;
  p.rel_half_width = rel_half_width(o.estimate);
  p.wall_s = wall_s;
  return p;
}

// Why the estimate should stop now, or empty.
std::string stop_rule(const RiskSpec& spec, const RiskParams& params, const RiskOutcome& o) {
  if (spec.rel_error > 0.0 && !o.estimate.upper_bound_only &&
      o.estimate.runs_with_events >= static_cast<std::size_t>(params.min_runs_with_events) &&
      rel_half_width(o.estimate) <= spec.rel_error) {
    return "rel-error";
  }
  if (o.simulated_h >= spec.budget_hours) return "budget";
  if (o.runs.size() >= spec.max_runs) return "max-runs";
  return {};
}

RunInputs load_inputs(const RiskSpec& spec, const RiskParams& params,
                      const planners::PlannerCatalog& catalog) {
  RunInputs in;
  in.track = run::load_track(spec.map);
  in.config = run::load_config(spec.config);
  in.entry = catalog.find(spec.policy);
  in.profile = *sim::parse_traffic_profile(spec.traffic);
  in.minutes = spec.minutes;
  in.event = spec.event;
  in.params = &params;
  return in;
}

}  // namespace

RiskOutcome run_risk(const RiskSpec& spec, const std::atomic<bool>* stop,
                     const std::function<void(const RiskProgress&)>& progress) {
  check_risk_spec(spec);
  const RiskParams params = load_risk_params(spec.params);
  const planners::PlannerCatalog builtins;
  const planners::PlannerCatalog& catalog = spec.planners ? *spec.planners : builtins;
  const RunInputs in = load_inputs(spec, params, catalog);
  const json identity = identity_of(spec, in, params);
  const auto t0 = std::chrono::steady_clock::now();
  const auto wall = [&t0] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };

  RiskOutcome o;
  o.params = params;
  o.runs = read_kept_runs(spec, identity);
  o.resumed_runs = o.runs.size();
  std::error_code ec;
  std::filesystem::create_directories(spec.out, ec);
  if (ec) throw std::runtime_error(spec.out.string() + ": cannot create (" + ec.message() + ")");
  write_text(spec.out / kSpecFile, identity.dump(2) + "\n");
  // Rewritten whole (a line cut short by a crash is gone), then appended to as runs finish.
  {
    std::string text;
    for (const RiskRun& r : o.runs) text += run_to_json(r).dump() + "\n";
    write_text(spec.out / kRunsFile, text);
  }
  std::ofstream runs_out(spec.out / kRunsFile, std::ios::app);
  if (!runs_out) throw std::runtime_error((spec.out / kRunsFile).string() + ": cannot write");

  sum_up(o);
  const eval::SplitLevels levels = params.levels();
  for (;;) {
    o.stopped_by = stop_rule(spec, params, o);
    if (!o.stopped_by.empty()) break;
    if (stop && stop->load()) {
      o.interrupted = true;
      o.stopped_by = "interrupted";
      break;
    }
    // The next batch: up to the end of the current block of batch_runs.
    const std::size_t first = o.runs.size();
    const auto block = static_cast<std::size_t>(params.batch_runs);
    const std::size_t end = std::min(spec.max_runs, (first / block + 1) * block);
    bool halted = false;
    const PoolOptions pool{spec.jobs, stop, PoolOrder::by_index, {}};
    const std::function<std::optional<RiskRun>(std::size_t, const std::atomic<bool>*)> work =
        [&](std::size_t i, const std::atomic<bool>* halt) -> std::optional<RiskRun> {
      RiskRun r;
      r.index = first + i;
      r.seed = spec.first_seed + r.index;
      const auto w0 = std::chrono::steady_clock::now();
      try {
        if (in.entry->kind != planners::PlannerKind::builtin) {
          const auto t = risk_detail::plain_run(in, spec, r.index, r.seed, halt);
          if (!t) return std::nullopt;
          r.tally = *t;
          r.tally.crossings.assign(levels.thresholds.size(), 0.0);
          r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
          return r;
        }
        const auto sys = risk_detail::make_world_branches(in, r.seed, halt);
        r.tally = eval::run_split(
            *sys, levels,
            {.max_paths = params.max_paths, .seed = core::derive_seed(r.seed, 0x7269736bULL)});
      } catch (const risk_detail::Interrupted&) {
        return std::nullopt;
      } catch (const eval::SplitExplosion& e) {
        throw std::runtime_error("run " + std::to_string(r.index) + " (seed " +
                                 std::to_string(r.seed) + "): " + e.what());
      } catch (const std::exception& e) {
        throw std::runtime_error("run " + std::to_string(r.index) + ": " + e.what());
      }
      r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
      return r;
    };
    const std::function<bool(std::size_t, std::optional<RiskRun> &&)> deliver =
        [&](std::size_t, std::optional<RiskRun>&& r) {
          if (!r || halted) {
            halted = true;  // the runs after a dropped one are dropped too: order is kept
            return true;
          }
          runs_out << run_to_json(*r).dump() << "\n" << std::flush;
          o.runs.push_back(std::move(*r));
          sum_up(o);
          if (progress) progress(progress_of(spec, o, wall()));
          return true;
        };
    (void)run_pool<std::optional<RiskRun>>(end - first, pool, work, deliver);
    if (halted || (stop && stop->load())) {
      o.interrupted = true;
      o.stopped_by = "interrupted";
      break;
    }
  }
  o.wall_s = wall();
  write_text(spec.out / "risk.json", risk_json(spec, o).dump(2) + "\n");
  write_text(spec.out / "summary.md", risk_markdown(spec, o));
  return o;
}

// ---------------------------------------------------------------------------------------
// Reports

namespace {

std::string risk_json_method(const RiskOutcome& o) {
  const bool splits =
      std::any_of(o.params.splits.begin(), o.params.splits.end(), [](int r) { return r > 1; });
  return splits ? "multilevel splitting on the margin to the nearest car"
                : "plain runs (the levels split nothing)";
}

}  // namespace

json risk_json(const RiskSpec& spec, const RiskOutcome& o) {
  const std::vector<double>& levels_m = o.params.margins_m;
  const double per = 1609.344 * kPer100Mi;  // per metre -> per 100 mi
  const eval::SplitEstimate& e = o.estimate;
  std::vector<double> crossings;
  std::size_t paths = 0;
  int base_events = 0;
  std::vector<double> y;
  for (const RiskRun& r : o.runs) {
    if (crossings.size() < r.tally.crossings.size()) crossings.resize(r.tally.crossings.size());
    for (std::size_t j = 0; j < r.tally.crossings.size(); ++j) crossings[j] += r.tally.crossings[j];
    paths += r.tally.paths;
    base_events += r.tally.base_events;
  }
  for (double& c : crossings) c = o.miles > 0 ? c / o.miles * kPer100Mi : 0.0;
  // The score's measurement: the share of the (weighted) events that came while the path's
  // score was at or above each level (the cycle before the event began).
  std::vector<double> recall(crossings.size(), 0.0);
  double all = 0.0;
  for (const RiskRun& r : o.runs) {
    for (const eval::SplitEvent& ev : r.tally.events) {
      all += ev.weight;
      for (int j = 0; j < ev.level && j < static_cast<int>(recall.size()); ++j) {
        recall[static_cast<std::size_t>(j)] += ev.weight;
      }
    }
  }
  for (double& x : recall) x = all > 0 ? x / all : 0.0;
  const double hours = o.base_h > 0 ? o.base_h : 1.0;
  json events = json::array();
  for (const RiskRun& r : o.runs) {
    for (const eval::SplitEvent& ev : r.tally.events) {
      events.push_back({{"run", r.index},
                        {"seed", r.seed},
                        {"t_s", ev.at},
                        {"branch_t_s", ev.base_cost},
                        {"path", ev.path},
                        {"level", ev.level},
                        {"weight", ev.weight}});
    }
  }
  json j = {{"event", spec.event.name()},
            {"policy", spec.policy},
            {"config", spec.config ? spec.config->string() : ""},
            {"map", spec.map ? spec.map->string() : "default"},
            {"traffic", spec.traffic},
            {"minutes_per_run", spec.minutes},
            {"first_seed", spec.first_seed},
            {"method", risk_json_method(o)},
            {"wall_s", o.wall_s},
            {"rate_per_100mi", e.rate * per},
            {"ci95_per_100mi", {e.ci.lo * per, e.ci.hi * per}},
            {"upper_bound_only", e.upper_bound_only},
            {"rate_per_hour", o.base_h > 0 ? e.rate * (o.miles * 1609.344) / hours : 0.0},
            {"effective_events", e.effective_events},
            {"runs", o.runs.size()},
            {"runs_with_events", e.runs_with_events},
            {"base_events", base_events},
            {"paths", paths},
            {"miles", o.miles},
            {"simulated_hours", o.simulated_h},
            {"base_hours", o.base_h},
            {"plain_mc_hours", o.plain_mc_h},
            {"gain", o.gain},
            {"stopped_by", o.stopped_by},
            {"interrupted", o.interrupted},
            {"resumed_runs", o.resumed_runs},
            {"rel_error", spec.rel_error},
            {"budget_hours", spec.budget_hours},
            {"levels_margin_m", levels_m},
            {"crossings_per_100mi", crossings},
            {"events_at_level_share", recall},
            {"events", events}};
  return j;
}

std::string risk_markdown(const RiskSpec& spec, const RiskOutcome& o) {
  const double per = 1609.344 * kPer100Mi;
  const eval::SplitEstimate& e = o.estimate;
  std::ostringstream s;
  s << "# risk: " << spec.event.name() << " events of " << spec.policy << "\n\n";
  s << "Map " << (spec.map ? spec.map->string() : "default") << ", " << spec.traffic
    << " traffic, runs of " << base::fixed_text(spec.minutes, 0) << " min from seed "
    << spec.first_seed << "; " << risk_json_method(o)
    << " (docs/evaluation.md, \"Rare events\").\n\n";
  s << "| figure | value |\n|---|---:|\n";
  if (e.upper_bound_only) {
    s << "| rate per 100 mi | 0 events; at most " << base::fixed_text(e.ci.hi * per, 4)
      << " (95%, one-sided, from the " << base::fixed_text(o.miles, 0)
      << " miles of the base runs as plain runs) |\n";
  } else {
    s << "| rate per 100 mi | " << base::fixed_text(e.rate * per, 4) << " |\n";
    s << "| 95% interval | " << base::fixed_text(e.ci.lo * per, 4) << " to "
      << base::fixed_text(e.ci.hi * per, 4) << " |\n";
    s << "| one event per | " << base::fixed_text(1.0 / (e.rate * 1609.344), 0) << " mi |\n";
    s << "| effective events | " << base::fixed_text(e.effective_events, 1) << " |\n";
  }
  s << "| base runs (with events) | " << o.runs.size() << " (" << e.runs_with_events << ") |\n";
  s << "| base miles | " << base::fixed_text(o.miles, 0) << " |\n";
  s << "| simulated hours (all paths) | " << base::fixed_text(o.simulated_h, 2) << " |\n";
  s << "| plain Monte Carlo hours, same variance | " << base::fixed_text(o.plain_mc_h, 2) << " |\n";
  s << "| gain | " << base::fixed_text(o.gain, 2) << "x |\n";
  s << "| stopped by | " << o.stopped_by << " |\n";
  s << "| wall time | " << base::fixed_text(o.wall_s, 1) << " s on " << spec.jobs << " jobs |\n";
  // The events of the base runs are plain runs' events: each is driven again, recorded and
  // cut into a scenario by these commands (a copy's event is not: it is a branch's).
  std::string repro;
  std::size_t shown = 0, base_events = 0;
  for (const RiskRun& r : o.runs) {
    for (const eval::SplitEvent& ev : r.tally.events) {
      if (ev.path != 0) continue;
      ++base_events;
      if (shown++ >= 20) continue;
      std::string drive = "overtake drive --policy " + spec.policy + " --seed " +
                          std::to_string(r.seed) + " --minutes " +
                          base::fixed_text(spec.minutes, 0) + " --traffic " + spec.traffic;
      if (spec.map) drive += " --map " + spec.map->string();
      if (spec.config) drive += " --config " + spec.config->string();
      const std::string replay = "run" + std::to_string(r.seed) + ".otr";
      repro += "- run " + std::to_string(r.index) + " (seed " + std::to_string(r.seed) + "), t " +
               base::fixed_text(ev.at, 2) + " s: `" + drive + " --record " + replay +
               "`, then `overtake cut " + replay + " --at " + base::fixed_text(ev.at, 2) +
               " -o event" + std::to_string(shown) + ".json" +
               (spec.config ? " --config " + spec.config->string() : "") + "`\n";
    }
  }
  if (base_events > 0) {
    s << "\n## The events of the base runs (" << base_events << ")\n\n"
      << "Each repeats when its run is driven again; recorded, it is cut into a scenario "
         "(docs/scenarios.md):\n\n"
      << repro;
    if (shown > 20) s << "- ... and " << (shown - 20) << " more (risk.json lists them all)\n";
  }
  return s.str();
}

// ---------------------------------------------------------------------------------------
// Two estimates compared

bool holds_risk(const std::filesystem::path& dir) {
  return std::filesystem::is_regular_file(dir / "risk.json");
}

namespace {

struct RiskFile {
  json j;
  eval::RateEstimate rate;
};

RiskFile read_risk_file(const std::filesystem::path& dir) {
  const auto file = dir / "risk.json";
  RiskFile f;
  f.j = run::read_json_file(file);
  const auto bad = [&](const std::string& why) {
    throw std::runtime_error(file.string() + ": " + why);
  };
  const auto number = [&](const char* key) {
    if (!f.j.contains(key) || !f.j[key].is_number()) bad(std::string(key) + " is not a number");
    const double x = f.j[key].get<double>();
    if (!std::isfinite(x) || x < 0.0) bad(std::string(key) + " is negative or not finite");
    return x;
  };
  if (!f.j.is_object() || !f.j.contains("event") || !f.j["event"].is_string())
    bad("not a risk estimate (no event)");
  f.rate.rate = number("rate_per_100mi");
  const json& ci = f.j.value("ci95_per_100mi", json());
  if (!ci.is_array() || ci.size() != 2 || !ci[0].is_number() || !ci[1].is_number())
    bad("ci95_per_100mi is not [low, high]");
  f.rate.ci = {ci[0].get<double>(), ci[1].get<double>()};
  if (!(f.rate.ci.lo >= 0.0 && f.rate.ci.lo <= f.rate.ci.hi && std::isfinite(f.rate.ci.hi)))
    bad("ci95_per_100mi is not an interval of rates");
  f.rate.upper_bound_only = f.j.value("upper_bound_only", false);
  return f;
}

}  // namespace

json compare_risk_folders(const std::filesystem::path& base,
                          const std::filesystem::path& candidate) {
  const RiskFile a = read_risk_file(base);
  const RiskFile b = read_risk_file(candidate);
  if (a.j["event"] != b.j["event"]) {
    throw std::runtime_error("the estimates count different events (" + a.j["event"].dump() +
                             " in " + base.string() + ", " + b.j["event"].dump() + " in " +
                             candidate.string() + "): their rates do not compare");
  }
  json notes = json::array();
  for (const char* key : {"map", "traffic", "minutes_per_run"}) {
    if (a.j.value(key, json()) != b.j.value(key, json())) {
      notes.push_back(std::string(key) + " differs (" + a.j.value(key, json()).dump() + ", " +
                      b.j.value(key, json()).dump() + "): the rates are of different roads");
    }
  }
  const eval::RateRatio r = eval::rate_ratio(a.rate, b.rate);
  const auto side = [](const RiskFile& f, const std::filesystem::path& dir) {
    std::string who = f.j.value("policy", "");
    if (!f.j.value("config", "").empty()) who += " with " + f.j.value("config", "");
    return json{{"folder", dir.string()},
                {"policy", who},
                {"rate_per_100mi", f.rate.rate},
                {"ci95_per_100mi", {f.rate.ci.lo, f.rate.ci.hi}},
                {"upper_bound_only", f.rate.upper_bound_only}};
  };
  json out = {
      {"event", a.j["event"]},
      {"base", side(a, base)},
      {"candidate", side(b, candidate)},
      {"ratio_defined", r.defined},
      {"ratio", r.ratio},
      {"ratio_ci95", {r.ci.lo, std::isfinite(r.ci.hi) ? json(r.ci.hi) : json(nullptr)}},
      {"verdict", r.verdict},
      {"method", "MOVER on the log scale from the two 95% intervals (independent estimates)"},
      {"notes", notes}};
  return out;
}

std::string compare_risk_text(const json& c) {
  std::ostringstream s;
  const auto rate_text = [](const json& side) {
    const json& ci = side["ci95_per_100mi"];
    if (side["upper_bound_only"].get<bool>()) {
      return "0 (at most " + base::fixed_text(ci[1].get<double>(), 4) + ")";
    }
    return base::fixed_text(side["rate_per_100mi"].get<double>(), 4) + " (" +
           base::fixed_text(ci[0].get<double>(), 4) + " to " +
           base::fixed_text(ci[1].get<double>(), 4) + ")";
  };
  s << "# " << c["event"].get<std::string>() << " events per 100 mi\n\n";
  s << "| | policy | rate (95% interval) |\n|---|---|---|\n";
  s << "| base | " << c["base"]["policy"].get<std::string>() << " | " << rate_text(c["base"])
    << " |\n";
  s << "| candidate | " << c["candidate"]["policy"].get<std::string>() << " | "
    << rate_text(c["candidate"]) << " |\n\n";
  const json& ci = c["ratio_ci95"];
  const std::string hi = ci[1].is_null() ? "infinity" : base::fixed_text(ci[1].get<double>(), 3);
  if (c["ratio_defined"].get<bool>()) {
    s << "candidate / base: " << base::fixed_text(c["ratio"].get<double>(), 3) << " (95% "
      << base::fixed_text(ci[0].get<double>(), 3) << " to " << hi
      << "): " << c["verdict"].get<std::string>() << "\n";
  } else {
    s << "candidate / base: at least " << base::fixed_text(ci[0].get<double>(), 3)
      << " (the base saw no event): " << c["verdict"].get<std::string>() << "\n";
  }
  for (const json& n : c["notes"]) s << "note: " << n.get<std::string>() << "\n";
  return s.str();
}

}  // namespace overtake::batch
