// `overtake hunt`: what a hunt found, as hunt.md and hunt.json.

#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "overtake/base/errors.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/hunt.hpp"

namespace overtake::batch {

using base::fixed_text;
using nlohmann::json;

std::string hunt_markdown(const HuntSpec& spec, const HuntOutcome& o) {
  std::ostringstream os;
  const double hours = o.simulated_s / 3600.0;
  os << "# hunt: " << spec.policy << "\n\n"
     << o.runs << " runs of " << fixed_text(spec.minutes, 1) << " min, " << fixed_text(hours, 2)
     << " simulated hours" << (o.interrupted ? " (interrupted)" : "")
     << (o.error.empty() ? "" : " (stopped by an error: " + o.error + ")") << ": "
     << o.failures.size() << (o.failures.size() == 1 ? " failure" : " failures") << " in "
     << o.groups.size() << (o.groups.size() == 1 ? " situation" : " situations") << ".\n\n";
  for (const HuntGroup& g : o.groups) {
    if (g.nondeterministic.empty()) continue;
    os << "**The planner is not deterministic**: " << g.nondeterministic << " (" << g.reactive
       << "). Its cut scenarios cannot be trusted to repeat its failures.\n\n";
    break;
  }
  os << "| situation | failures | scenario (reactive / replayed) | repeats the failure (reactive "
        "/ replayed) | reproduce |\n|---|---:|---|---|---|\n";
  for (const HuntGroup& g : o.groups) {
    const std::string scenarios = g.reactive.empty() && g.replayed.empty()
                                      ? "could not cut: " + g.cut_error
                                      : g.reactive + " / " + g.replayed;
    const std::string repeats =
        g.reproduces_reactive.empty()
            ? std::string("-")
            : g.reproduces_reactive + " / " + g.reproduces_replayed +
                  (g.warm_up.empty() ? std::string() : "; warm-up " + g.warm_up) +
                  (g.nondeterministic.empty() ? std::string()
                                              : "; NOT DETERMINISTIC: " + g.nondeterministic);
    os << "| " << g.situation << " | " << g.failures.size() << " | " << scenarios << " | "
       << repeats << " | `" << g.repro << "` |\n";
  }
  os << "\n| # | t s | what | seed | traffic | map | replay | run again "
        "|\n|---:|---:|---|---:|---|---|---|---|\n";
  for (std::size_t i = 0; i < o.failures.size(); ++i) {
    const HuntFailure& f = o.failures[i];
    os << "| " << i + 1 << " | " << fixed_text(f.t_s, 2) << " | " << f.what << " | " << f.seed
       << " | " << f.traffic << " | " << f.map << " | " << f.replay << " | `" << f.rerun << "` |\n";
  }
  return os.str();
}

nlohmann::json hunt_json(const HuntSpec& spec, const HuntOutcome& o) {
  json failures = json::array();
  for (const HuntFailure& f : o.failures) {
    failures.push_back({{"run", f.run},
                        {"seed", f.seed},
                        {"traffic", f.traffic},
                        {"map", f.map},
                        {"t_s", f.t_s},
                        {"what", f.what},
                        {"situation", f.situation},
                        {"replay", f.replay},
                        {"rerun", f.rerun}});
  }
  json groups = json::array();
  for (const HuntGroup& g : o.groups) {
    groups.push_back(
        {{"situation", g.situation},
         {"failures", g.failures},
         {"reactive", g.reactive},
         {"replayed", g.replayed},
         {"cut_error", g.cut_error},
         {"reproduces", {{"reactive", g.reproduces_reactive}, {"replayed", g.reproduces_replayed}}},
         {"reproduced", g.reproduced},
         {"warm_up", g.warm_up.empty() ? json(nullptr) : json(g.warm_up)},
         {"nondeterministic",
          g.nondeterministic.empty() ? json(nullptr) : json(g.nondeterministic)},
         {"repro", g.repro}});
  }
  json j = {{"policy", spec.policy},
            {"minutes", spec.minutes},
            {"runs", o.runs},
            {"simulated_hours", o.simulated_s / 3600.0},
            {"interrupted", o.interrupted},
            {"error", o.error.empty() ? json(nullptr) : json(o.error)},
            {"failures", failures},
            {"groups", groups},
            {"timing", {{"wall_s", o.wall_s}}}};
  if (o.shard) {
    j["shard"] = {{"index", spec.shard_index},           {"count", spec.shard_count},
                  {"finished", o.shard->finished},       {"max_runs", o.shard->max_runs},
                  {"run_seconds", o.shard->run_seconds}, {"sweep", o.shard->sweep},
                  {"revision", o.shard->revision}};
  }
  return j;
}

int report_hunt(const HuntSpec& spec, const HuntOutcome& o, bool quiet) {
  if (!quiet) {
    std::cout << hunt_markdown(spec, o);
    const double rate = o.wall_s > 0 ? (o.simulated_s / 3600.0) / (o.wall_s / 60.0) : 0;
    std::printf(
        "%.2f simulated hours in %.1f s on %d jobs: %.1f simulated hours per "
        "wall-clock minute\n",
        o.simulated_s / 3600.0, o.wall_s, spec.jobs, rate);
    std::cout << "written: " << spec.out.string() << "/{hunt.md,hunt.json,replays,scenarios}\n";
  }
  if (o.interrupted) {
    std::cerr << "hunt: interrupted; " << o.failures.size() << " failures kept in "
              << spec.out.string() << "\n";
    return base::kExitInterrupted;
  }
  return base::kExitOk;
}

}  // namespace overtake::batch
