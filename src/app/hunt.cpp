#include "overtake/app/hunt.hpp"

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <iostream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "overtake/app/cli.hpp"
#include "overtake/app/commands.hpp"
#include "overtake/app/cut.hpp"
#include "overtake/app/interrupt.hpp"
#include "overtake/app/io.hpp"
#include "overtake/app/report.hpp"
#include "overtake/core/road.hpp"
#include "overtake/replay/replay.hpp"

namespace overtake::app {
namespace {

using nlohmann::json;

constexpr int kMaxJobs = 256;
constexpr int kMaxFailures = 10000;
/// Below this the ego counts as standing, below the next as slow.
constexpr double kStandingMps = 0.5;
constexpr double kSlowMps = 10.0;
/// Further than this from its lane's centre, the ego is between lanes.
constexpr double kBetweenLanesM = 1.0;
/// An incident of the same type (and car) within this of the last is a repeat of it.
constexpr double kRepeatS = 1.5;

std::string map_name(const std::optional<std::filesystem::path>& map) {
  return map ? map->string() : std::string("default");
}

std::string slug(const std::string& text) {
  std::string out;
  for (const char c : text) {
    const bool keep = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    if (keep) {
      out += c;
    } else if (!out.empty() && out.back() != '-') {
      out += '-';
    }
  }
  while (!out.empty() && out.back() == '-') out.pop_back();
  return out.empty() ? "run" : out;
}

bool counts(const sim::Incident& i, HuntTarget target) {
  switch (target) {
    case HuntTarget::collisions:
      return i.type == sim::IncidentType::collision;
    case HuntTarget::at_fault:
      return i.type == sim::IncidentType::collision && (!i.collision || i.collision->at_fault);
    case HuntTarget::incidents:
      return true;
  }
  return false;
}

std::string what_of(const sim::Incident& i) {
  std::string text(sim::to_string(i.type));
  if (i.collision) {
    text += std::string(" ") + std::string(sim::to_string(i.collision->kind)) +
            (i.collision->at_fault ? " (at fault)" : " (not at fault)");
  }
  return text;
}

/// The situation of a failure: what happened, the traffic, and the ego then (standing, slow
/// or at speed; in its lane or between lanes), read from the replay's frame.
std::string situation_of(const sim::Incident& i, const std::string& traffic,
                         const replay::Replay& r, const core::RoadParams& road) {
  std::string speed = "ego at speed";
  std::string where = "in its lane";
  const auto step = static_cast<long>(std::lround(i.t_s / r.header.step_s));
  for (const replay::ReplayFrame& f : r.frames) {
    if (f.step != step) continue;
    speed = f.speed_mps < kStandingMps ? "ego standing"
            : f.speed_mps < kSlowMps   ? "ego slow"
                                       : "ego at speed";
    const int lane = std::clamp(core::lane_of(f.d_m, road), 0, road.lane_count - 1);
    if (std::abs(f.d_m - core::lane_center_d(lane, road)) > kBetweenLanesM) where = "between lanes";
    break;
  }
  return what_of(i) + ", " + traffic + " traffic, " + speed + ", " + where;
}

struct Combo {
  std::uint64_t seed = 0;
  std::optional<std::filesystem::path> map;
  std::string traffic;
};

Combo combo_of(const HuntSpec& spec, std::size_t k) {
  const std::size_t per_seed = spec.maps.size() * spec.traffic.size();
  const std::size_t within = k % per_seed;
  return {spec.first_seed + k / per_seed, spec.maps[within / spec.traffic.size()],
          spec.traffic[within % spec.traffic.size()]};
}

std::string shell_quoted(const std::string& text) {
  std::string out = "'";
  for (const char ch : text) out += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return out + "'";
}

/// The command and flags that give a run the hunt's planner: `drive --policy P` for a
/// built-in policy, the flag that brings a plugin or a Python planner, `sim --planner-cmd`
/// for a planner program.
std::string planner_command(const HuntSpec& spec) {
  const PlannerEntry* e = spec.planners ? spec.planners->find(spec.policy) : nullptr;
  const std::string named = e ? shell_quoted(e->name + "=" + e->source) : std::string();
  if (!e || e->kind == PlannerKind::builtin) return "overtake drive --policy " + spec.policy;
  switch (e->kind) {
    case PlannerKind::plugin:
      return "overtake drive --policy-lib " + named;
    case PlannerKind::python:
      return "overtake drive --policy-py " + named;
    case PlannerKind::program:
      return "overtake sim --planner-cmd " + shell_quoted(e->source) + " --planner-name " +
             shell_quoted(e->name);
    case PlannerKind::builtin:
      break;
  }
  return "overtake drive --policy " + spec.policy;
}

std::string rerun_command(const HuntSpec& spec, const Combo& c, const std::string& replay) {
  std::string cmd = planner_command(spec) + " --traffic " + c.traffic + " --seed " +
                    std::to_string(c.seed) + " --minutes " + fixed_text(spec.minutes, 1);
  if (c.map) cmd += " --map " + c.map->string();
  if (spec.config) cmd += " --config " + spec.config->string();
  return cmd + " --record " + replay;
}

/// A finished run, waiting to be taken in order.
struct RunResult {
  bool stopped = false;
  std::string error;
  sim::RunReport report;
  std::filesystem::path replay;
};

void check_spec(const HuntSpec& spec) {
  if (spec.jobs < 1 || spec.jobs > kMaxJobs) {
    throw UsageError("--jobs must be between 1 and " + std::to_string(kMaxJobs));
  }
  if (spec.failures < 1 || spec.failures > kMaxFailures) {
    throw UsageError("--failures must be between 1 and " + std::to_string(kMaxFailures));
  }
  if (!(spec.budget_hours > 0.0) || !std::isfinite(spec.budget_hours)) {
    throw UsageError("--budget-hours must be more than 0");
  }
  if (spec.maps.empty()) throw UsageError("--maps: no map given");
  if (spec.traffic.empty()) throw UsageError("--traffic: no traffic profile given");
  DriveOptions o;
  o.policy = spec.policy;
  o.planners = spec.planners;
  o.minutes = spec.minutes;
  validate_drive_options(o);
  for (const auto& t : spec.traffic) {
    o.traffic = t;
    validate_drive_options(o);
  }
  if (!(spec.before_s >= 0.0) || !(spec.after_s >= 0.0)) {
    throw UsageError("--before and --after must be at least 0");
  }
}

}  // namespace

HuntOutcome run_hunt(const HuntSpec& spec, const std::atomic<bool>* stop,
                     const std::function<void(const HuntProgress&)>& progress) {
  check_spec(spec);
  const Config config = load_config(spec.config);
  std::vector<std::shared_ptr<const Track>> tracks;
  for (const auto& m : spec.maps) tracks.push_back(load_track(m));
  std::error_code ec;
  for (const char* sub : {"runs", "replays", "scenarios", "logs"}) {
    std::filesystem::create_directories(spec.out / sub, ec);
    if (ec)
      throw std::runtime_error((spec.out / sub).string() + ": cannot create (" + ec.message() +
                               ")");
  }
  const auto max_runs = static_cast<std::size_t>(
      std::max(1.0, std::floor(spec.budget_hours * 60.0 / spec.minutes + 1e-9)));

  std::mutex mu;
  std::condition_variable cv;
  std::map<std::size_t, RunResult> results;  // finished, not yet taken
  std::atomic<std::size_t> next{0};
  std::atomic<bool> enough{false};
  // Runs in progress end (as stopped) once the hunt has enough, or the user stops it.
  std::atomic<bool> halt{false};
  const auto stopping = [&] { return enough.load() || (stop && stop->load()); };
  const auto wall0 = std::chrono::steady_clock::now();

  const auto worker = [&] {
    while (!stopping()) {
      const std::size_t k = next.fetch_add(1);
      if (k >= max_runs) return;
      const Combo c = combo_of(spec, k);
      RunResult res;
      DriveOptions o;
      o.policy = spec.policy;
      o.planners = spec.planners;
      o.traffic = c.traffic;
      o.seed = c.seed;
      o.minutes = spec.minutes;
      o.map = c.map;
      res.replay = spec.out / "runs" / ("run" + std::to_string(k) + ".otr");
      o.record = res.replay;
      o.planner_log = spec.out / "logs" / ("run" + std::to_string(k) + ".log");
      try {
        const std::size_t m = static_cast<std::size_t>(
            std::find(spec.maps.begin(), spec.maps.end(), c.map) - spec.maps.begin());
        const DriveResult r = drive_on(*tracks[m], config, o, {}, &halt);
        res.report = r.report;
        res.stopped = r.report.outcome.end == sim::RunEnd::stopped;
      } catch (const std::exception& e) {
        res.error = e.what();
      }
      std::lock_guard lock(mu);
      results.emplace(k, std::move(res));
      cv.notify_all();
    }
  };
  const int threads = std::min<int>(spec.jobs, static_cast<int>(max_runs));
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);

  HuntOutcome out;
  std::map<std::string, std::size_t> group_of;
  HuntProgress prog;
  prog.budget_s = static_cast<double>(max_runs) * spec.minutes * 60.0;
  std::string failure;
  const auto write_reports = [&] {
    out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    write_file_atomic(spec.out / "hunt.md", hunt_markdown(spec, out));
    write_file_atomic(spec.out / "hunt.json", hunt_json(spec, out).dump(2) + "\n");
  };
  std::size_t taken = 0;
  while (taken < max_runs) {
    RunResult res;
    {
      std::unique_lock lock(mu);
      const bool ready = cv.wait_for(lock, std::chrono::milliseconds(200),
                                     [&] { return results.count(taken) > 0; });
      if (stop && stop->load()) halt = true;
      if (progress) {
        prog.wall_s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
        progress(prog);
      }
      if (!ready) {
        if (stopping() && next.load() <= taken) break;  // nobody will bring it
        continue;  // (interrupted: the run waited for ends as stopped soon)
      }
      res = std::move(results[taken]);
      results.erase(taken);
    }
    const std::size_t k = taken++;
    if (res.stopped) break;  // interrupted mid-run: not a finished run
    if (!res.error.empty()) {
      failure = "run " + std::to_string(k) + ": " + res.error;
      enough = true;
      break;
    }
    ++out.runs;
    out.simulated_s += res.report.duration_s;
    prog.runs = out.runs;
    prog.simulated_s = out.simulated_s;
    const Combo c = combo_of(spec, k);
    // One failure per episode: the referee counts a contact (or a speeding, a straddle)
    // again each second it lasts; those repeats are the same failure.
    std::vector<const sim::Incident*> found;
    // A planner that fails (stalls, crashes, sends what cannot be read) is a failure too.
    const bool planner_failed = res.report.outcome.end == sim::RunEnd::planner_failed &&
                                static_cast<int>(out.failures.size()) < spec.failures;
    std::map<std::pair<int, long>, double> last_seen;  // (type, car) -> time of its last count
    for (const sim::Incident& i : res.report.incidents) {
      if (!counts(i, spec.target)) continue;
      const std::pair<int, long> key{
          static_cast<int>(i.type),
          i.type == sim::IncidentType::collision ? std::lround(i.value) : -1};
      const auto it = last_seen.find(key);
      const bool repeat = it != last_seen.end() && i.t_s - it->second <= kRepeatS;
      last_seen[key] = i.t_s;
      if (!repeat && static_cast<int>(out.failures.size() + found.size()) < spec.failures) {
        found.push_back(&i);
      }
    }
    if (found.empty() && !planner_failed) {
      std::filesystem::remove(res.replay, ec);
      continue;
    }
    const std::string base = slug(spec.policy + "-" + map_name(c.map) + "-" + c.traffic + "-seed" +
                                  std::to_string(c.seed));
    const std::filesystem::path kept = spec.out / "replays" / (base + ".otr");
    std::filesystem::rename(res.replay, kept, ec);
    if (ec)
      throw std::runtime_error(kept.string() + ": cannot keep the replay (" + ec.message() + ")");
    const replay::Replay r = replay::read_replay(kept);
    if (planner_failed) found.push_back(nullptr);
    for (const sim::Incident* i : found) {
      HuntFailure f;
      f.run = k;
      f.seed = c.seed;
      f.traffic = c.traffic;
      f.map = map_name(c.map);
      if (i) {
        f.t_s = i->t_s;
        f.what = what_of(*i);
        f.situation = situation_of(*i, c.traffic, r, config.road);
      } else {
        f.t_s = res.report.outcome.t_s;
        f.what = "the planner failed: " + res.report.outcome.reason.substr(0, 200);
        f.situation = "the planner failed, " + c.traffic + " traffic";
      }
      f.replay = (std::filesystem::path("replays") / (base + ".otr")).generic_string();
      f.rerun = rerun_command(spec, c, f.replay);
      const std::size_t index = out.failures.size();
      out.failures.push_back(f);
      auto [it, is_new] = group_of.emplace(f.situation, out.groups.size());
      if (is_new) {
        HuntGroup g;
        g.situation = f.situation;
        const std::string stem = "scenarios/" + slug(base + "-t" + fixed_text(f.t_s, 2));
        for (const bool replayed : {false, true}) {
          CutOptions co;
          co.replay = kept;
          co.at_s = f.t_s;
          co.before_s = spec.before_s;
          co.after_s = spec.after_s;
          co.replayed = replayed;
          co.config = spec.config;
          co.map = c.map;
          co.out = spec.out / (stem + (replayed ? ".replayed.json" : ".reactive.json"));
          co.description = "Found by overtake hunt: " + f.what + " of " + spec.policy + " at t " +
                           fixed_text(f.t_s, 2) + " s (" + f.situation + "; " + c.traffic +
                           " traffic, seed " + std::to_string(c.seed) + ", map " + f.map + ").";
          try {
            (void)cut_replay(co);
          } catch (const std::exception& e) {
            throw std::runtime_error("cutting " + co.out.string() + ": " + e.what());
          }
        }
        g.reactive = stem + ".reactive.json";
        g.replayed = stem + ".replayed.json";
        g.repro = "overtake drive --scenario " + (spec.out / g.reactive).string() + " --policy " +
                  spec.policy;
        out.groups.push_back(std::move(g));
      }
      out.groups[it->second].failures.push_back(index);
    }
    prog.failures = out.failures.size();
    prog.groups = out.groups.size();
    write_reports();
    if (static_cast<int>(out.failures.size()) >= spec.failures) {
      enough = true;
      break;
    }
  }
  enough = true;
  halt = true;
  for (auto& t : pool) t.join();
  // Runs past the last one taken are not part of the hunt.
  for (auto& [k, res] : results) std::filesystem::remove(res.replay, ec);
  for (const auto& e : std::filesystem::directory_iterator(spec.out / "runs", ec)) {
    std::filesystem::remove(e.path(), ec);
  }
  if (!failure.empty()) throw std::runtime_error(failure);
  out.interrupted = stop && stop->load() && static_cast<int>(out.failures.size()) < spec.failures &&
                    taken < max_runs;
  write_reports();
  if (progress) {
    prog.wall_s = out.wall_s;
    progress(prog);
  }
  return out;
}

std::string hunt_markdown(const HuntSpec& spec, const HuntOutcome& o) {
  std::ostringstream os;
  const double hours = o.simulated_s / 3600.0;
  os << "# hunt: " << spec.policy << "\n\n"
     << o.runs << " runs of " << fixed_text(spec.minutes, 1) << " min, " << fixed_text(hours, 2)
     << " simulated hours" << (o.interrupted ? " (interrupted)" : "") << ": " << o.failures.size()
     << (o.failures.size() == 1 ? " failure" : " failures") << " in " << o.groups.size()
     << (o.groups.size() == 1 ? " situation" : " situations") << ".\n\n";
  os << "| situation | failures | scenario (reactive / replayed) | reproduce "
        "|\n|---|---:|---|---|\n";
  for (const HuntGroup& g : o.groups) {
    const std::string scenarios = g.reactive.empty() && g.replayed.empty()
                                      ? "could not cut: " + g.cut_error
                                      : g.reactive + " / " + g.replayed;
    os << "| " << g.situation << " | " << g.failures.size() << " | " << scenarios << " | `"
       << g.repro << "` |\n";
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
    groups.push_back({{"situation", g.situation},
                      {"failures", g.failures},
                      {"reactive", g.reactive},
                      {"replayed", g.replayed},
                      {"cut_error", g.cut_error},
                      {"repro", g.repro}});
  }
  return {{"policy", spec.policy},
          {"minutes", spec.minutes},
          {"runs", o.runs},
          {"simulated_hours", o.simulated_s / 3600.0},
          {"interrupted", o.interrupted},
          {"failures", failures},
          {"groups", groups},
          {"timing", {{"wall_s", o.wall_s}}}};
}

}  // namespace overtake::app

namespace overtake::app {

Subcommand register_hunt(CLI::App& app) {
  struct State {
    HuntSpec spec;
    PlannerFlags planners;
    std::string maps, traffic = "faithful,calm", find = "collisions", config, out = "hunt-out";
    CLI::Option* policy_opt = nullptr;
    bool quiet = false;
  };
  auto st = std::make_shared<State>();
  st->spec.jobs = static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
  auto* cmd = app.add_subcommand(
      "hunt",
      "Drive one planner over seeds, maps and traffic profiles in parallel until it has failed\n"
      "--failures times or --budget-hours of simulation are spent. For each distinct failure\n"
      "(grouped by kind and situation) it keeps the replay, cuts a scenario with reactive and\n"
      "one with replayed traffic, and prints the command that reproduces it (hunt.md,\n"
      "hunt.json in --out). Ctrl-C keeps what was found (docs/scenarios.md).");
  st->policy_opt =
      cmd->add_option("--policy", st->spec.policy, policy_help())->capture_default_str();
  add_planner_flags(*cmd, st->planners, PlannerFlagSet::all);
  cmd->add_option("--failures,-n", st->spec.failures, "Stop after this many failures")
      ->capture_default_str();
  cmd->add_option("--budget-hours", st->spec.budget_hours, "... or after this many simulated hours")
      ->capture_default_str();
  cmd->add_option("--find", st->find,
                  "What counts as a failure: collisions, at-fault (collisions that were the\n"
                  "ego's fault) or incidents (any incident)")
      ->capture_default_str();
  cmd->add_option("--first-seed", st->spec.first_seed, "Seeds go up from this one")
      ->capture_default_str();
  cmd->add_option("--maps", st->maps,
                  "Comma-separated map files to drive on (\"default\" for the built-in track;\n"
                  "default: the built-in track)");
  cmd->add_option("--traffic", st->traffic, "Comma-separated traffic profiles")
      ->capture_default_str();
  cmd->add_option("--minutes", st->spec.minutes, "Simulated minutes per run")
      ->capture_default_str();
  cmd->add_option("--before", st->spec.before_s, "The cut scenarios start this long before")
      ->capture_default_str();
  cmd->add_option("--after", st->spec.after_s, "... and end this long after the failure")
      ->capture_default_str();
  cmd->add_option("--config", st->config, "JSON parameter overrides")->check(CLI::ExistingFile);
  cmd->add_option("--jobs,-j", st->spec.jobs, "Runs in parallel (default: all cores)")
      ->capture_default_str();
  cmd->add_option("--out,-o", st->out, "Output folder")->capture_default_str();
  cmd->add_flag("--quiet,-q", st->quiet, "No progress line or table");
  return {
      cmd, [st] {
        HuntSpec spec = st->spec;
        spec.planners = catalog_from_flags(st->planners);
        spec.policy = chosen_policy(*spec.planners, spec.policy, st->policy_opt->count() > 0);
        if (st->find == "collisions") {
          spec.target = HuntTarget::collisions;
        } else if (st->find == "at-fault") {
          spec.target = HuntTarget::at_fault;
        } else if (st->find == "incidents") {
          spec.target = HuntTarget::incidents;
        } else {
          throw UsageError("--find: '" + st->find + "' is none of collisions, at-fault, incidents");
        }
        if (!st->maps.empty()) {
          spec.maps.clear();
          std::string cur;
          std::istringstream in(st->maps);
          while (std::getline(in, cur, ',')) {
            if (cur.empty()) continue;
            if (cur == "default") {
              spec.maps.emplace_back(std::nullopt);
            } else {
              if (!std::filesystem::is_regular_file(cur)) {
                throw UsageError("--maps: " + cur + " is not a file");
              }
              spec.maps.emplace_back(cur);
            }
          }
        }
        spec.traffic = split_list(st->traffic);
        if (!st->config.empty()) spec.config = st->config;
        spec.out = st->out;
        const bool draw = !st->quiet && stderr_is_terminal();
        HuntOutcome o;
        {
          const InterruptScope interrupt;
          o = run_hunt(spec, &InterruptScope::flag(), [&](const HuntProgress& p) {
            if (!draw) return;
            const double rate = p.wall_s > 0 ? (p.simulated_s / 3600.0) / (p.wall_s / 60.0) : 0;
            const double left_s =
                p.simulated_s > 0 ? p.wall_s * (p.budget_s - p.simulated_s) / p.simulated_s : 0;
            std::fprintf(stderr,
                         "\r  hunt: %zu runs, %.1f of %.1f simulated h, %zu failures in %zu "
                         "situations, %.1f sim-h/min, at most %.0f s to go   ",
                         p.runs, p.simulated_s / 3600.0, p.budget_s / 3600.0, p.failures, p.groups,
                         rate, left_s);
            std::fflush(stderr);
          });
          if (draw) std::fprintf(stderr, "\n");
        }
        if (!st->quiet) {
          std::cout << hunt_markdown(spec, o);
          const double rate = o.wall_s > 0 ? (o.simulated_s / 3600.0) / (o.wall_s / 60.0) : 0;
          std::printf(
              "%.2f simulated hours in %.1f s on %d jobs: %.1f simulated hours per "
              "wall-clock minute\n",
              o.simulated_s / 3600.0, o.wall_s, spec.jobs, rate);
          std::cout << "written: " << spec.out.string()
                    << "/{hunt.md,hunt.json,replays,scenarios}\n";
        }
        if (o.interrupted) {
          std::cerr << "hunt: interrupted; " << o.failures.size() << " failures kept in "
                    << spec.out.string() << "\n";
          return kExitInterrupted;
        }
        return kExitOk;
      }};
}

}  // namespace overtake::app
