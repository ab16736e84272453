// `overtake risk`: the estimate's loop (base runs in batches, each split), its stopping rules,
// the runs kept in --out for --resume, and what it reports.

#include "overtake/batch/risk.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
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
  if (spec.scenarios < 0 || spec.scenarios > 10000)
    throw UsageError("--scenarios must be from 0 (none) to 10000 (got " +
                     std::to_string(spec.scenarios) + ")");
  check_jobs(spec.jobs);
  check_shard(spec.shard);
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

// The identity of a shard's runs: the estimate's, and which slice.
json shard_identity(const RiskSpec& spec, const RunInputs& in, const RiskParams& params) {
  json j = identity_of(spec, in, params);
  if (spec.shard.count > 1) j["shard"] = spec.shard.text();
  return j;
}

json failures_json(const RiskRun& r) {
  json failures = json::array();
  for (const RiskFailure& f : r.failures) {
    failures.push_back({{"path", f.path}, {"t_s", f.t_s}, {"reason", f.reason}});
  }
  return failures;
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
          {"planner_failures", failures_json(r)},
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
  // (Runs written before planner failures were kept have none.)
  if (j.contains("planner_failures")) {
    for (const json& f : j.at("planner_failures")) {
      r.failures.push_back({f.at("path").get<std::size_t>(), f.at("t_s").get<double>(),
                            f.at("reason").get<std::string>()});
    }
  }
  r.wall_s = j.at("wall_s").get<double>();
  return r;
}

// The runs of a runs.jsonl. A last line cut short by a crash is dropped (its run is done
// again); any other that cannot be read is a UsageError naming the file and line.
std::vector<RiskRun> read_runs_file(const std::filesystem::path& file, const std::string& flag) {
  std::ifstream in(file);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::vector<RiskRun> runs;
  for (std::size_t n = 0; n < lines.size(); ++n) {
    try {
      runs.push_back(run_from_json(json::parse(lines[n])));
    } catch (const std::exception& e) {
      if (n + 1 == lines.size()) break;
      throw UsageError(flag + file.string() + " line " + std::to_string(n + 1) + ": " + e.what());
    }
  }
  return runs;
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
  if (kept.contains("shard") && !identity.contains("shard")) {
    throw UsageError("--resume: " + spec.out.string() + " holds shard " +
                     kept["shard"].get<std::string>() +
                     " of an estimate; give --shard, or merge it with --merge");
  }
  for (const auto& [key, v] : identity.items()) {
    if (!kept.contains(key) || kept[key] != v) {
      throw UsageError("--resume: the estimate in " + spec.out.string() + " is of another " + key +
                       " (" + (kept.contains(key) ? kept[key].dump() : "none") + ", now " +
                       v.dump() + "); choose another --out");
    }
  }
  std::vector<RiskRun> runs = read_runs_file(runs_file, "--resume: ");
  for (std::size_t j = 0; j < runs.size(); ++j) {
    if (runs[j].index != spec.shard.item(j)) {
      throw UsageError("--resume: " + runs_file.string() + " line " + std::to_string(j + 1) +
                       ": run " + std::to_string(runs[j].index) + " where run " +
                       std::to_string(spec.shard.item(j)) + " was next");
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

// A planner that failed in every run so far gives nothing to estimate (a rate of no miles):
// the estimate ends there, naming the first failure, its runs kept.
void refuse_when_every_run_failed(const RiskSpec& spec, const RiskOutcome& o) {
  if (o.runs.empty() ||
      !std::all_of(o.runs.begin(), o.runs.end(), [](const RiskRun& r) { return r.base_failed(); }))
    return;
  const RiskRun& first = o.runs.front();
  const RiskFailure& f = first.failures.front();
  throw std::runtime_error("the planner failed in every one of the " +
                           std::to_string(o.runs.size()) + " runs so far (the first: run " +
                           std::to_string(first.index) + ", seed " + std::to_string(first.seed) +
                           ", at t = " + base::fixed_text(f.t_s, 2) + " s: " + f.reason +
                           "); there is nothing to estimate (its runs are kept in " +
                           (spec.out / kRunsFile).string() + ")");
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

// Base run `index` and its copies; nullopt when it was stopped.
std::optional<RiskRun> one_run(const RiskSpec& spec, const RunInputs& in,
                               const eval::SplitLevels& levels, std::size_t index,
                               const std::atomic<bool>* halt) {
  RiskRun r;
  r.index = index;
  r.seed = spec.first_seed + index;
  const auto w0 = std::chrono::steady_clock::now();
  try {
    if (in.entry->kind != planners::PlannerKind::builtin) {
      std::optional<RiskFailure> failure;
      const auto t = risk_detail::plain_run(in, spec, r.index, r.seed, halt, failure);
      if (!t) return std::nullopt;
      r.tally = *t;
      r.tally.crossings.assign(levels.thresholds.size(), 0.0);
      if (failure) r.failures.push_back(std::move(*failure));
    } else {
      const auto sys = risk_detail::make_world_branches(in, r.seed, halt, &r.failures);
      r.tally = eval::run_split(
          *sys, levels,
          {.max_paths = in.params->max_paths, .seed = core::derive_seed(r.seed, 0x7269736bULL)});
    }
  } catch (const risk_detail::Interrupted&) {
    return std::nullopt;
  } catch (const eval::SplitExplosion& e) {
    throw std::runtime_error("run " + std::to_string(r.index) + " (seed " + std::to_string(r.seed) +
                             "): " + e.what());
  } catch (const std::exception& e) {
    throw std::runtime_error("run " + std::to_string(r.index) + ": " + e.what());
  }
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  return r;
}

// The runs of the next batch: to the end of the current block of batch_runs; for a shard, its
// next batch_runs runs among the planned ones. Empty when a shard has run them all.
std::vector<std::size_t> next_batch(const RiskSpec& spec, const RiskParams& params,
                                    std::size_t done) {
  const auto block = static_cast<std::size_t>(params.batch_runs);
  std::vector<std::size_t> batch;
  if (spec.shard.count > 1) {
    const std::size_t planned = risk_detail::planned_runs(spec, params);
    for (std::size_t j = done; batch.size() < block && spec.shard.item(j) < planned; ++j) {
      batch.push_back(spec.shard.item(j));
    }
    return batch;
  }
  const std::size_t end = std::min(spec.max_runs, (done / block + 1) * block);
  for (std::size_t k = done; k < end; ++k) batch.push_back(k);
  return batch;
}

// The estimate's files: risk-spec.json, runs.jsonl (rewritten whole: a line cut short by a
// crash is gone), and the stream runs.jsonl is appended to as runs finish.
std::ofstream open_runs(const RiskSpec& spec, const json& identity, const RiskOutcome& o) {
  std::error_code ec;
  std::filesystem::create_directories(spec.out, ec);
  if (ec) throw std::runtime_error(spec.out.string() + ": cannot create (" + ec.message() + ")");
  write_text(spec.out / kSpecFile, identity.dump(2) + "\n");
  std::string text;
  for (const RiskRun& r : o.runs) text += run_to_json(r).dump() + "\n";
  write_text(spec.out / kRunsFile, text);
  std::ofstream runs_out(spec.out / kRunsFile, std::ios::app);
  if (!runs_out) throw std::runtime_error((spec.out / kRunsFile).string() + ": cannot write");
  return runs_out;
}

// risk.json first (a cut that fails or is stopped loses none of the estimate), then the events
// cut into scenarios (not by a shard: by its merge), then risk.json again and summary.md.
void write_outcome(const RiskSpec& spec, RiskOutcome& o, const std::atomic<bool>* stop) {
  write_text(spec.out / "risk.json", risk_json(spec, o).dump(2) + "\n");
  if (!o.interrupted && spec.shard.count == 1) {
    risk_detail::cut_events(spec, o, stop);
    write_text(spec.out / "risk.json", risk_json(spec, o).dump(2) + "\n");
  }
  write_text(spec.out / "summary.md", risk_markdown(spec, o));
}

struct Loaded {
  RiskParams params;
  planners::PlannerCatalog builtins;
  RunInputs in;
};

std::unique_ptr<Loaded> load_estimate(const RiskSpec& spec) {
  check_risk_spec(spec);
  auto l = std::make_unique<Loaded>();
  l->params = load_risk_params(spec.params);
  const planners::PlannerCatalog& catalog = spec.planners ? *spec.planners : l->builtins;
  l->in = load_inputs(spec, l->params, catalog);
  return l;
}

}  // namespace

std::size_t risk_runs_planned(const RiskSpec& spec) {
  return risk_detail::planned_runs(spec, load_risk_params(spec.params));
}

std::size_t risk_detail::planned_runs(const RiskSpec& spec, const RiskParams& params) {
  const auto block = static_cast<double>(params.batch_runs);
  const double bought = std::ceil(spec.budget_hours * 60.0 / spec.minutes / block) * block;
  return std::min(spec.max_runs, static_cast<std::size_t>(std::max(bought, block)));
}

RiskOutcome run_risk(const RiskSpec& spec, const std::atomic<bool>* stop,
                     const std::function<void(const RiskProgress&)>& progress) {
  const auto loaded = load_estimate(spec);
  const RiskParams& params = loaded->params;
  const RunInputs& in = loaded->in;
  const json identity = shard_identity(spec, in, params);
  const auto t0 = std::chrono::steady_clock::now();
  const auto wall = [&t0] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };

  RiskOutcome o;
  o.params = params;
  o.runs = read_kept_runs(spec, identity);
  o.resumed_runs = o.runs.size();
  std::ofstream runs_out = open_runs(spec, identity, o);

  sum_up(o);
  const eval::SplitLevels levels = params.levels();
  for (;;) {
    // A shard runs its planned runs whatever the estimate: the stopping rules are the merge's.
    const std::vector<std::size_t> batch = next_batch(spec, params, o.runs.size());
    o.stopped_by =
        spec.shard.count > 1 ? (batch.empty() ? "shard" : "") : stop_rule(spec, params, o);
    if (!o.stopped_by.empty()) break;
    if (stop && stop->load()) {
      o.interrupted = true;
      o.stopped_by = "interrupted";
      break;
    }
    bool halted = false;
    const PoolOptions pool{spec.jobs, stop, PoolOrder::by_index, {}};
    const std::function<std::optional<RiskRun>(std::size_t, const std::atomic<bool>*)> work =
        [&](std::size_t i, const std::atomic<bool>* halt) {
          return one_run(spec, in, levels, batch[i], halt);
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
    (void)run_pool<std::optional<RiskRun>>(batch.size(), pool, work, deliver);
    refuse_when_every_run_failed(spec, o);
    if (halted || (stop && stop->load())) {
      o.interrupted = true;
      o.stopped_by = "interrupted";
      break;
    }
  }
  o.wall_s = wall();
  write_outcome(spec, o, stop);
  return o;
}

namespace {

// The runs of the shard in `dir`, checked to be of the estimate `identity` names; its shard in
// `shard`.
std::vector<RiskRun> read_shard(const std::filesystem::path& dir, const json& identity,
                                Shard& shard) {
  const std::string name = "--merge: " + dir.string();
  json kept;
  try {
    kept = run::read_json_file(dir / kSpecFile);
  } catch (const std::exception& e) {
    throw UsageError(name + " is not a shard of an estimate (" + e.what() + ")");
  }
  for (const auto& [key, v] : identity.items()) {
    if (!kept.contains(key) || kept[key] != v) {
      throw UsageError(name + " is a shard of another " + key + " (" +
                       (kept.contains(key) ? kept[key].dump() : "none") + ", here " + v.dump() +
                       ")");
    }
  }
  shard = Shard{};
  if (kept.contains("shard")) {
    try {
      shard = parse_shard(kept["shard"].get<std::string>());
    } catch (const std::exception& e) {
      throw UsageError(name + ": " + kSpecFile + ": " + e.what());
    }
  }
  std::vector<RiskRun> runs = read_runs_file(dir / kRunsFile, "--merge: ");
  for (const RiskRun& r : runs) {
    if (!shard.holds(r.index) || r.seed != identity["first_seed"].get<std::uint64_t>() + r.index) {
      throw UsageError(name + ": run " + std::to_string(r.index) + " (seed " +
                       std::to_string(r.seed) + ") is not one of shard " + shard.text() + "'s");
    }
  }
  return runs;
}

}  // namespace

RiskOutcome merge_risk(const RiskSpec& spec, const std::vector<std::filesystem::path>& shards,
                       const std::atomic<bool>* stop) {
  if (shards.empty()) throw UsageError("--merge: give the shards' folders");
  if (spec.shard.count > 1) throw UsageError("--merge writes the whole estimate: no --shard");
  const auto loaded = load_estimate(spec);
  const RiskParams& params = loaded->params;
  const json identity = identity_of(spec, loaded->in, params);
  if (std::filesystem::exists(spec.out / kSpecFile) ||
      std::filesystem::exists(spec.out / kRunsFile)) {
    throw UsageError("--out: " + spec.out.string() +
                     " already holds an estimate; the shards merge into a folder of their own");
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::map<std::size_t, RiskRun> all;
  std::set<int> seen;
  int count = 0;
  for (const auto& dir : shards) {
    Shard shard;
    std::vector<RiskRun> runs = read_shard(dir, identity, shard);
    if (count != 0 && shard.count != count) {
      throw UsageError("--merge: " + dir.string() + " is shard " + shard.text() +
                       ", the others are of " + std::to_string(count));
    }
    count = shard.count;
    if (!seen.insert(shard.index).second) {
      throw UsageError("--merge: shard " + shard.text() + " is given twice (" + dir.string() + ")");
    }
    for (RiskRun& r : runs) all.emplace(r.index, std::move(r));
  }
  // The runs from 0 without a gap, then the stopping rules after each block, as run_risk looks
  // at them: where they stop, the estimate here stops.
  std::vector<RiskRun> prefix;
  for (auto it = all.find(0); it != all.end() && it->first == prefix.size(); ++it) {
    prefix.push_back(std::move(it->second));
  }
  RiskOutcome o;
  o.params = params;
  const auto block = static_cast<std::size_t>(params.batch_runs);
  for (std::size_t n = 0;;) {
    o.runs.assign(prefix.begin(), prefix.begin() + static_cast<std::ptrdiff_t>(n));
    sum_up(o);
    o.stopped_by = stop_rule(spec, params, o);
    if (!o.stopped_by.empty()) break;
    if (n == prefix.size()) {
      o.stopped_by = "shards";  // the runs the shards hold end here
      break;
    }
    n = std::min({prefix.size(), spec.max_runs, (n / block + 1) * block});
  }
  o.merged_note = std::to_string(seen.size()) + " of " + std::to_string(count) + " shards, " +
                  std::to_string(all.size()) + " runs, " + std::to_string(prefix.size()) +
                  " of them from run 0 without a gap; the stopping rules kept " +
                  std::to_string(o.runs.size());
  { std::ofstream runs_out = open_runs(spec, identity, o); }
  refuse_when_every_run_failed(spec, o);
  o.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_outcome(spec, o, stop);
  return o;
}

}  // namespace overtake::batch
