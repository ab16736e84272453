// `overtake risk`'s reports: risk.json's figures and the summary (summary.md, and what the
// command prints), the events cut into scenarios among them.

#include <algorithm>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/risk.hpp"
#include "risk_internal.hpp"

namespace overtake::batch {

using nlohmann::json;

namespace {

constexpr double kPer100Mi = 100.0;

}  // namespace

namespace {

// The events cut into scenarios: the hunt's groups (OUT/events/hunt.md has them all).
json cut_json(const RiskSpec& spec, const RiskOutcome& o) {
  json j = {{"folder", o.cut ? json(risk_detail::kEventsDir) : json(nullptr)},
            {"asked", spec.scenarios},
            {"note", o.cut_note}};
  if (!o.cut) return j;
  json groups = json::array();
  std::size_t repeating = 0;
  for (const HuntGroup& g : o.cut->groups) {
    if (g.reproduced) ++repeating;
    groups.push_back({{"situation", g.situation},
                      {"events", g.failures.size()},
                      {"reactive", g.reactive},
                      {"replayed", g.replayed},
                      {"repeats", g.reproduced},
                      {"cut_error", g.cut_error},
                      {"repro", g.repro}});
  }
  j["events"] = o.cut->failures.size();
  j["groups"] = std::move(groups);
  j["groups_repeating"] = repeating;
  return j;
}

// The paths the planner ended, every run's, in run order.
struct FailureRow {
  const RiskRun* run = nullptr;
  const RiskFailure* failure = nullptr;
};
std::vector<FailureRow> failure_rows(const RiskOutcome& o) {
  std::vector<FailureRow> rows;
  for (const RiskRun& r : o.runs) {
    for (const RiskFailure& f : r.failures) rows.push_back({&r, &f});
  }
  return rows;
}

std::size_t runs_ended_by_planner(const RiskOutcome& o) {
  return static_cast<std::size_t>(std::count_if(o.runs.begin(), o.runs.end(),
                                                [](const RiskRun& r) { return r.base_failed(); }));
}

// The command that drives the estimate's planner (a planner from outside with its flags).
std::string drive_command(const RiskSpec& spec) {
  const planners::PlannerEntry* e = spec.planners ? spec.planners->find(spec.policy) : nullptr;
  if (e) return planners::planner_command_line(planners::call_of(*e));
  return planners::planner_command_line(
      {planners::PlannerKind::builtin, spec.policy, {}, {}, 4567});
}

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
            {"mean_speed_mph", o.base_h > 0.0 ? o.miles / o.base_h : 0.0},
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
  json failures = json::array();
  for (const FailureRow& f : failure_rows(o)) {
    failures.push_back({{"run", f.run->index},
                        {"seed", f.run->seed},
                        {"path", f.failure->path},
                        {"t_s", f.failure->t_s},
                        {"reason", f.failure->reason}});
  }
  j["runs_ended_by_planner"] = runs_ended_by_planner(o);
  j["planner_failures"] = std::move(failures);
  j["scenarios"] = cut_json(spec, o);
  if (spec.shard.count > 1) {
    j["shard"] = {{"index", spec.shard.index},
                  {"count", spec.shard.count},
                  {"planned_runs", risk_detail::planned_runs(spec, o.params)},
                  {"finished", !o.interrupted}};
  }
  if (!o.merged_note.empty()) j["merged"] = o.merged_note;
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
  const std::vector<FailureRow> failed = failure_rows(o);
  if (!failed.empty()) {
    s << "| ended by the planner's failure | " << runs_ended_by_planner(o) << " of "
      << o.runs.size() << " runs";
    if (failed.size() > runs_ended_by_planner(o)) {
      s << ", " << failed.size() - runs_ended_by_planner(o) << " copies";
    }
    s << " (each counts what it drove until then; a failure is not the event) |\n";
  }
  s << "| stopped by | " << o.stopped_by << " |\n";
  if (spec.shard.count > 1) {
    s << "| shard | " << spec.shard.text() << " of the "
      << risk_detail::planned_runs(spec, o.params)
      << " planned runs (the stopping rules are the merge's) |\n";
  }
  if (!o.merged_note.empty()) s << "| merged | " << o.merged_note << " |\n";
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
      std::string drive = drive_command(spec) + " --seed " + std::to_string(r.seed) +
                          " --minutes " + base::fixed_text(spec.minutes, 0) + " --traffic " +
                          spec.traffic;
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
  if (!failed.empty()) {
    s << "\n## The planner's failures (" << failed.size() << ")\n\n"
      << "Each ended its path there: the miles and events before it count, the rest of the run "
         "was not driven. A failure is the planner's, never the event; a planner that fails "
         "often makes the rate one of the miles it could drive.\n\n";
    for (std::size_t k = 0; k < failed.size() && k < 20; ++k) {
      const FailureRow& f = failed[k];
      s << "- run " << f.run->index << " (seed " << f.run->seed << ")"
        << (f.failure->path == 0 ? "" : ", copy " + std::to_string(f.failure->path)) << ", t "
        << base::fixed_text(f.failure->t_s, 2) << " s: " << f.failure->reason << "\n";
    }
    if (failed.size() > 20) s << "- ... and " << (failed.size() - 20) << " more (risk.json)\n";
  }
  if (o.cut) {
    s << "\n## The events cut into scenarios\n\n"
      << o.cut->failures.size() << " event" << (o.cut->failures.size() == 1 ? "" : "s")
      << " of the base runs in " << o.cut->groups.size() << " situation"
      << (o.cut->groups.size() == 1 ? "" : "s") << ", each group's first cut into scenarios in "
      << (spec.out / risk_detail::kEventsDir).string()
      << " (hunt.md there has them all):\n\n| situation | events | repeats | reproduce |\n"
         "|---|---:|---|---|\n";
    for (const HuntGroup& g : o.cut->groups) {
      s << "| " << g.situation << " | " << g.failures.size() << " | "
        << (g.cut_error.empty() ? (g.reproduced ? "yes" : "no: " + g.reproduces_reactive)
                                : "could not cut: " + g.cut_error)
        << " | `" << g.repro << "` |\n";
    }
  }
  if (!o.cut_note.empty()) s << "\n" << o.cut_note << "\n";
  if (base_events > 0 && !o.cut) {
    s << "\n## The events of the base runs (" << base_events << ")\n\n"
      << "Each repeats when its run is driven again; recorded, it is cut into a scenario "
         "(docs/scenarios.md):\n\n"
      << repro;
    if (shown > 20) s << "- ... and " << (shown - 20) << " more (risk.json lists them all)\n";
  }
  return s.str();
}

int report_risk(const RiskSpec& spec, const RiskOutcome& o, const std::filesystem::path& json_out,
                bool quiet, const std::string& how) {
  if (!json_out.empty()) base::write_file_atomic(json_out, risk_json(spec, o).dump(2) + "\n");
  if (!quiet) {
    std::cout << risk_markdown(spec, o) << how;
    std::cout << "written: " << spec.out.string() << "/{risk.json,summary.md,runs.jsonl}"
              << (o.cut ? ", " + (spec.out / "events").string() + "/ (the cut scenarios)" : "")
              << "\n";
  }
  if (o.interrupted) {
    std::cerr << "risk: interrupted; " << o.runs.size() << " runs kept in " << spec.out.string()
              << " (--resume goes on with them)\n";
    return base::kExitInterrupted;
  }
  return base::kExitOk;
}

}  // namespace overtake::batch
