#include "overtake/app/hunt.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "overtake/app/bench.hpp"
#include "overtake/app/build_info.hpp"
#include "overtake/app/cli.hpp"
#include "overtake/app/commands.hpp"
#include "overtake/app/config.hpp"
#include "overtake/app/cut.hpp"
#include "overtake/app/interrupt.hpp"
#include "overtake/app/io.hpp"
#include "overtake/app/report.hpp"
#include "overtake/app/reproduce.hpp"
#include "overtake/app/slurm.hpp"
#include "overtake/core/hash.hpp"
#include "overtake/core/road.hpp"
#include "overtake/core/text_check.hpp"
#include "overtake/replay/replay.hpp"

namespace overtake::app {
namespace {

using nlohmann::json;

constexpr int kMaxJobs = 256;
constexpr int kMaxFailures = 10000;
/// The largest budget of simulated time (h; some 11 years), and the most runs a hunt takes.
constexpr double kMaxBudgetHours = 100000.0;
constexpr std::size_t kMaxHuntRuns = 100000000;
/// Hex digits of a map's name's hash that tell apart maps whose slugs are the same.
constexpr std::size_t kMapTagHashDigits = 8;
/// The files a hunt writes into its folder, and the folders whose files it names after the runs
/// (a folder of another's that holds them is not replaced without --force).
constexpr std::array<const char*, 2> kHuntReports = {"hunt.json", "hunt.md"};
constexpr std::array<const char*, 2> kHuntFolders = {"replays", "scenarios"};
/// The folder of the runs in progress (their replays until a run is taken).
constexpr const char* kRunsDir = "runs";
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
  std::size_t map_index = 0;  ///< into HuntSpec::maps
  std::optional<std::filesystem::path> map;
  std::string traffic;
};

Combo combo_of(const HuntSpec& spec, std::size_t k) {
  const std::size_t per_seed = spec.maps.size() * spec.traffic.size();
  const std::size_t within = k % per_seed;
  const std::size_t m = within / spec.traffic.size();
  return {spec.first_seed + k / per_seed, m, spec.maps[m],
          spec.traffic[within % spec.traffic.size()]};
}

/// Each map's part of the names of its runs' files: its name as a slug, and where two maps'
/// slugs are the same (mp/seed_2.csv, mp/seed-2.csv) a short hash of its whole name too, so
/// that no run's replay takes the place of another's.
std::vector<std::string> map_tags(const std::vector<std::optional<std::filesystem::path>>& maps) {
  std::vector<std::string> tags;
  for (const auto& m : maps) tags.push_back(slug(map_name(m)));
  const auto clashes = [&](std::size_t i) {
    return std::count(tags.begin(), tags.end(), tags[i]) > 1;
  };
  std::vector<std::string> out = tags;
  for (std::size_t i = 0; i < maps.size(); ++i) {
    if (clashes(i)) {
      out[i] += "-" + core::hex64(core::fnv1a64(map_name(maps[i]))).substr(0, kMapTagHashDigits);
    }
  }
  tags = out;
  for (std::size_t i = 0; i < maps.size(); ++i) {  // hashes alike too: the map's place
    if (clashes(i)) out[i] += "-m" + std::to_string(i + 1);
  }
  return out;
}

/// The command and flags that give a run the hunt's planner: `drive --policy P` for a
/// built-in policy, the flag that brings a plugin or a Python planner, `sim --planner-cmd`
/// for a planner program.
std::string planner_command(const HuntSpec& spec) {
  const PlannerEntry* e = spec.planners ? spec.planners->find(spec.policy) : nullptr;
  if (e) return planner_command_line(call_of(*e));
  return planner_command_line({PlannerKind::builtin, spec.policy, {}, {}, 4567});
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

}  // namespace

std::size_t hunt_max_runs(const HuntSpec& spec) {
  const double runs = std::floor(spec.budget_hours * 60.0 / spec.minutes + 1e-9);
  // Saturated before the conversion: a budget check_spec refuses gives no wrapped count.
  if (!(runs < static_cast<double>(kMaxHuntRuns))) return kMaxHuntRuns;
  return static_cast<std::size_t>(std::max(1.0, runs));
}

std::string hunt_run_name(const HuntSpec& spec, std::size_t run) {
  const Combo c = combo_of(spec, run);
  return slug(spec.policy + "-" + map_tags(spec.maps)[c.map_index] + "-" + c.traffic + "-seed" +
              std::to_string(c.seed));
}

namespace {

void check_spec(const HuntSpec& spec) {
  if (spec.jobs < 1 || spec.jobs > kMaxJobs) {
    throw UsageError("--jobs must be between 1 and " + std::to_string(kMaxJobs));
  }
  if (spec.failures < 1 || spec.failures > kMaxFailures) {
    throw UsageError("--failures must be between 1 and " + std::to_string(kMaxFailures));
  }
  if (!(spec.budget_hours > 0.0) || !(spec.budget_hours <= kMaxBudgetHours)) {
    std::ostringstream os;
    os << "--budget-hours must be more than 0 and at most " << kMaxBudgetHours << " (got "
       << spec.budget_hours << ")";
    throw UsageError(os.str());
  }
  if (spec.maps.empty()) throw UsageError("--maps: no map given");
  if (spec.traffic.empty()) throw UsageError("--traffic: no traffic profile given");
  for (std::size_t i = 0; i < spec.maps.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      const auto& a = spec.maps[j];
      const auto& b = spec.maps[i];
      if (a.has_value() == b.has_value() && (!a || same_file(*a, *b))) {
        throw UsageError("--maps: " + map_name(b) + " is named twice (items " +
                         std::to_string(j + 1) + " and " + std::to_string(i + 1) +
                         "); each map is driven once, name it once");
      }
    }
  }
  check_unique_names(spec.traffic, "--traffic");
  DriveOptions o;
  o.policy = spec.policy;
  o.planners = spec.planners;
  o.minutes = spec.minutes;
  validate_drive_options(o);
  for (const auto& t : spec.traffic) {
    o.traffic = t;
    validate_drive_options(o);
  }
  // Each failure's scenarios are cut as `overtake cut` cuts them: the same bounds, checked now.
  check_cut_window(spec.before_s, spec.after_s);
  const std::size_t runs = hunt_max_runs(spec);
  if (static_cast<double>(runs) >= static_cast<double>(kMaxHuntRuns)) {
    throw UsageError("--budget-hours over --minutes gives more than " +
                     std::to_string(kMaxHuntRuns - 1) +
                     " runs; give a smaller budget or longer runs");
  }
  const std::size_t per_seed = spec.maps.size() * spec.traffic.size();
  const std::uint64_t last_offset = (runs - 1) / per_seed;
  if (spec.first_seed > std::numeric_limits<std::uint64_t>::max() - last_offset) {
    throw UsageError("--first-seed: the hunt's seeds go from " + std::to_string(spec.first_seed) +
                     " up " + std::to_string(last_offset) + " more, past the last seed (" +
                     std::to_string(std::numeric_limits<std::uint64_t>::max()) + ")");
  }
  if (spec.shard_count < 1 || spec.shard_index < 1 || spec.shard_index > spec.shard_count) {
    throw UsageError("--shard: " + std::to_string(spec.shard_index) + "/" +
                     std::to_string(spec.shard_count) + " is out of range");
  }
  if (static_cast<std::size_t>(spec.shard_count) > hunt_max_runs(spec)) {
    throw UsageError("--shard: " + std::to_string(spec.shard_count) + " shards of a hunt of " +
                     std::to_string(hunt_max_runs(spec)) +
                     " runs (--budget-hours over --minutes); a shard needs at least one run");
  }
}

// What makes the shards of a hunt one hunt: every flag that changes what it finds.
json hunt_sweep(const HuntSpec& spec, const Config& config) {
  std::vector<std::string> maps;
  for (const auto& m : spec.maps) maps.push_back(map_name(m));
  json planner = nullptr;
  const PlannerEntry* e = spec.planners ? spec.planners->find(spec.policy) : nullptr;
  if (e && e->kind != PlannerKind::builtin) planner = json::parse(e->describe());
  return {{"policy", spec.policy},
          {"planner", planner},
          {"minutes", spec.minutes},
          {"failures", spec.failures},
          {"budget_hours", spec.budget_hours},
          {"find", static_cast<int>(spec.target)},
          {"traffic", spec.traffic},
          {"maps", maps},
          {"first_seed", spec.first_seed},
          {"before_s", spec.before_s},
          {"warm_up", spec.warm_up_all ? json("all") : json(spec.warm_up_s)},
          {"after_s", spec.after_s},
          {"params_hash", config_hash(config)},
          {"shards", spec.shard_count}};
}

}  // namespace

namespace {

// The hunt's maps, each once: two files with the same contents are one map driven twice.
std::vector<std::shared_ptr<const Track>> load_hunt_tracks(const HuntSpec& spec) {
  std::vector<std::shared_ptr<const Track>> tracks;
  for (std::size_t i = 0; i < spec.maps.size(); ++i) {
    tracks.push_back(load_track(spec.maps[i]));
    for (std::size_t j = 0; j < i; ++j) {
      if (tracks[j]->map.content_hash == tracks[i]->map.content_hash) {
        throw UsageError("--maps: " + map_name(spec.maps[i]) + " is the same map as " +
                         map_name(spec.maps[j]) + " (hash " +
                         core::hex64(tracks[i]->map.content_hash) +
                         "); each map is driven once, name it once");
      }
    }
  }
  return tracks;
}

// A replay of a run in progress, as the recorder names it: runK.otr, its FILE.partial or
// FILE.N.partial. Nothing else in runs/ is removed.
bool is_run_file(const std::string& name) {
  std::size_t at = 0;
  const auto digits = [&] {
    const std::size_t from = at;
    while (at < name.size() && name[at] >= '0' && name[at] <= '9') ++at;
    return at > from;
  };
  const auto word = [&](std::string_view w) {
    if (name.compare(at, w.size(), w) != 0) return false;
    at += w.size();
    return true;
  };
  if (!word("run") || !digits() || !word(".otr")) return false;
  if (at == name.size()) return true;
  if (word(".partial")) return at == name.size();
  return word(".") && digits() && word(".partial") && at == name.size();
}

void remove_run_files(const std::filesystem::path& dir) {
  std::error_code ec;
  std::vector<std::filesystem::path> doomed;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    if (is_run_file(e.path().filename().string())) doomed.push_back(e.path());
  }
  for (const auto& p : doomed) std::filesystem::remove(p, ec);
}

}  // namespace

void check_hunt_out(const std::filesystem::path& out, bool force, const std::string& who,
                    const std::string& remedy) {
  if (force) return;
  std::error_code ec;
  for (const char* name : kHuntReports) {
    const std::filesystem::path file = out / name;
    if (!std::filesystem::exists(std::filesystem::symlink_status(file, ec))) continue;
    throw UsageError(who + file.string() + " exists" +
                     (std::string(name) == "hunt.json" ? " (a hunt's results)" : "") +
                     ": a hunt would replace it; " + remedy);
  }
  for (const char* name : kHuntFolders) {
    const std::filesystem::path dir = out / name;
    if (!std::filesystem::exists(std::filesystem::symlink_status(dir, ec))) continue;
    if (!std::filesystem::is_directory(dir, ec) || !std::filesystem::is_empty(dir, ec)) {
      throw UsageError(who + dir.string() +
                       " is not empty and the folder holds no hunt.json: a hunt would replace "
                       "files in it; " +
                       remedy);
    }
  }
}

void check_hunt_spec(const HuntSpec& spec) {
  check_spec(spec);
  (void)load_config(spec.config);
  (void)load_hunt_tracks(spec);
}

namespace {

/// Drives a group's two scenarios at once with the hunt's planner: do they repeat the failure
/// at its step? The reactive one is driven a second time: a planner that answers differently
/// when told the same is named. False when a warm-up did not bring the planner in step.
bool check_group(const HuntSpec& spec, const Track& track, const Config& config,
                 const FailureMark& mark, HuntGroup& g, const std::atomic<bool>* stop) {
  DriveOptions base;
  base.policy = spec.policy;
  base.planners = spec.planners;
  const auto log_of = [&](const std::string& scenario, const char* what) {
    return spec.out / "logs" /
           (std::filesystem::path(scenario).stem().string() + "." + what + ".log");
  };
  base.planner_log = log_of(g.reactive, "check");
  const ReproCheck reactive =
      check_reproduction(track, config, base, spec.out / g.reactive, mark, stop);
  base.planner_log = log_of(g.replayed, "check");
  const ReproCheck replayed =
      check_reproduction(track, config, base, spec.out / g.replayed, mark, stop);
  g.reproduces_reactive = reactive.text;
  g.reproduces_replayed = replayed.text;
  g.reproduced = reactive.reproduced && replayed.reproduced;
  g.nondeterministic.clear();
  const auto in_step = [](const ReproCheck& r) {
    return !r.report.warm_up || r.report.warm_up->in_step;
  };
  if (reactive.stopped || replayed.stopped) return true;
  // Told the same twice: a planner whose answers differ is not deterministic (even when its
  // failure happened to come again).
  base.planner_log = log_of(g.reactive, "again");
  const ReproCheck again =
      check_reproduction(track, config, base, spec.out / g.reactive, mark, stop);
  if (!again.stopped) g.nondeterministic = drives_differ(reactive, again);
  return in_step(reactive) && in_step(replayed);
}

}  // namespace

HuntOutcome run_hunt(const HuntSpec& spec, const std::atomic<bool>* stop,
                     const std::function<void(const HuntProgress&)>& progress) {
  check_spec(spec);
  const Config config = load_config(spec.config);
  const std::vector<std::shared_ptr<const Track>> tracks = load_hunt_tracks(spec);
  check_hunt_out(spec.out, spec.force,
                 "--out: ", "move it away, choose another --out, or give --force to replace it");
  std::error_code ec;
  for (const char* sub : {kRunsDir, "replays", "scenarios", "logs"}) {
    std::filesystem::create_directories(spec.out / sub, ec);
    if (ec)
      throw std::runtime_error((spec.out / sub).string() + ": cannot create (" + ec.message() +
                               ")");
  }
  const std::size_t max_runs = hunt_max_runs(spec);
  // This shard's runs: the j-th is run offset + stride * j of the hunt.
  const auto offset = static_cast<std::size_t>(spec.shard_index - 1);
  const auto stride = static_cast<std::size_t>(spec.shard_count);
  const std::size_t shard_runs = max_runs > offset ? (max_runs - offset + stride - 1) / stride : 0;
  const auto run_of = [&](std::size_t j) { return offset + stride * j; };

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
      const std::size_t j = next.fetch_add(1);
      if (j >= shard_runs) return;
      const std::size_t k = run_of(j);
      const Combo c = combo_of(spec, k);
      RunResult res;
      DriveOptions o;
      o.policy = spec.policy;
      o.planners = spec.planners;
      o.traffic = c.traffic;
      o.seed = c.seed;
      o.minutes = spec.minutes;
      o.map = c.map;
      res.replay = spec.out / kRunsDir / ("run" + std::to_string(k) + ".otr");
      o.record = res.replay;
      o.planner_log = spec.out / "logs" / ("run" + std::to_string(k) + ".log");
      try {
        const DriveResult r = drive_on(*tracks[c.map_index], config, o, {}, &halt);
        res.report = r.report;
        res.stopped = r.report.outcome.end == sim::RunEnd::stopped;
      } catch (const std::exception& e) {
        res.error = e.what();
      }
      std::lock_guard lock(mu);
      results.emplace(j, std::move(res));
      cv.notify_all();
    }
  };
  std::vector<std::thread> pool;

  HuntOutcome out;
  if (spec.shard_count > 1) {
    out.shard.emplace();
    out.shard->max_runs = max_runs;
    out.shard->sweep = hunt_sweep(spec, config);
    out.shard->revision = std::string(build_revision());
  }
  std::map<std::string, std::size_t> group_of;
  HuntProgress prog;
  prog.budget_s = static_cast<double>(shard_runs) * spec.minutes * 60.0;
  // The outcome (hunt.json) first: a hunt.md that cannot be written loses nothing found.
  const auto write_reports = [&] {
    out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    write_file_atomic(spec.out / "hunt.json", json_text(hunt_json(spec, out), 2) + "\n");
    write_file_atomic(spec.out / "hunt.md", hunt_markdown(spec, out));
  };
  std::size_t taken = 0;
  std::string failure;  // why the hunt stopped before its end, when something failed
  // Whatever ends the hunt (enough failures, a stop, an error anywhere in here), the workers
  // stop and are joined below before it returns or throws.
  try {
    const int threads = std::min<int>(spec.jobs, static_cast<int>(shard_runs));
    for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
    while (taken < shard_runs) {
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
      const std::size_t k = run_of(taken++);
      if (res.stopped) break;  // interrupted mid-run: not a finished run
      if (!res.error.empty()) {
        failure = "run " + std::to_string(k) + ": " + res.error;
        break;
      }
      ++out.runs;
      out.simulated_s += res.report.duration_s;
      if (out.shard) out.shard->run_seconds.emplace_back(k, res.report.duration_s);
      prog.runs = out.runs;
      prog.simulated_s = out.simulated_s;
      const Combo c = combo_of(spec, k);
      // One failure per contact (a collision) or per episode (another incident): the referee
      // counts a contact, a speeding or a straddle again each second it lasts; those repeats
      // are the same failure.
      std::vector<sim::Incident> found;
      // A planner that fails (stalls, crashes, sends what cannot be read) is a failure too.
      const bool planner_failed = res.report.outcome.end == sim::RunEnd::planner_failed &&
                                  static_cast<int>(out.failures.size()) < spec.failures;
      const auto room = [&] {
        return static_cast<int>(out.failures.size() + found.size()) < spec.failures;
      };
      if (spec.target != HuntTarget::incidents) {
        for (std::size_t n = 0; n < res.report.contacts.size(); ++n) {
          const sim::Contact& contact = res.report.contacts[n];
          if (spec.target == HuntTarget::at_fault && !contact.collision.at_fault) continue;
          if (room()) found.push_back(contact_incident(contact, static_cast<int>(n)));
        }
      } else {
        std::map<int, double> last_seen;  // type -> time of its last count
        std::set<int> contacts_seen;
        for (const sim::Incident& i : res.report.incidents) {
          bool repeat = false;
          if (i.type == sim::IncidentType::collision && i.contact >= 0) {
            repeat = !contacts_seen.insert(i.contact).second;
          } else {
            const auto it = last_seen.find(static_cast<int>(i.type));
            repeat = it != last_seen.end() && i.t_s - it->second <= kRepeatS;
            last_seen[static_cast<int>(i.type)] = i.t_s;
          }
          if (!repeat && room()) found.push_back(i);
        }
      }
      if (found.empty() && !planner_failed) {
        std::filesystem::remove(res.replay, ec);
        continue;
      }
      const std::string base = hunt_run_name(spec, k);
      const std::filesystem::path kept = spec.out / "replays" / (base + ".otr");
      std::filesystem::rename(res.replay, kept, ec);
      if (ec)
        throw std::runtime_error(kept.string() + ": cannot keep the replay (" + ec.message() + ")");
      const replay::Replay r = replay::read_replay(kept);
      std::vector<const sim::Incident*> failures;
      for (const sim::Incident& i : found) failures.push_back(&i);
      if (planner_failed) failures.push_back(nullptr);
      std::vector<std::size_t> new_groups;       // their scenarios are cut once the run is written
      std::map<std::size_t, FailureMark> marks;  // each new group's first failure
      for (const sim::Incident* i : failures) {
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
          g.repro = f.rerun;  // until its scenario is cut
          g.cut_error = "not cut yet";
          FailureMark mark;
          mark.t_s = f.t_s;
          if (i) mark.incident = *i;
          marks[out.groups.size()] = mark;
          new_groups.push_back(out.groups.size());
          out.groups.push_back(std::move(g));
        }
        out.groups[it->second].failures.push_back(index);
      }
      prog.failures = out.failures.size();
      prog.groups = out.groups.size();
      // The failures are written before their scenarios are cut: a cut that fails loses none.
      write_reports();
      for (const std::size_t gi : new_groups) {
        HuntGroup& g = out.groups[gi];
        const HuntFailure& f = out.failures[g.failures.front()];
        const std::string stem = "scenarios/" + slug(base + "-t" + fixed_text(f.t_s, 2));
        // Cut with the hunt's warm-up; a planner from outside that does not come in step in it
        // is cut again with every cycle from the run's first (its state is then the run's, if
        // it is deterministic), and checked again.
        const auto cut_and_check = [&](bool all) {
          g.cut_error.clear();
          for (const bool replayed : {false, true}) {
            CutOptions co;
            co.replay = kept;
            co.at_s = f.t_s;
            co.before_s = spec.before_s;
            co.after_s = spec.after_s;
            co.replayed = replayed;
            co.warm_up_s = spec.warm_up_s;
            co.warm_up_all = all;
            co.config = spec.config;
            co.map = c.map;
            co.out = spec.out / (stem + (replayed ? ".replayed.json" : ".reactive.json"));
            co.description = "Found by overtake hunt: " + f.what + " of " + spec.policy + " at t " +
                             fixed_text(f.t_s, 2) + " s (" + f.situation + "; " + c.traffic +
                             " traffic, seed " + std::to_string(c.seed) + ", map " + f.map + ").";
            try {
              (void)cut_replay(co);
            } catch (const std::exception& e) {
              // The failure stays, with its replay and the command that drives its run again.
              g.cut_error =
                  (replayed ? "replayed traffic: " : "reactive traffic: ") + std::string(e.what());
              break;
            }
          }
          if (!g.cut_error.empty()) {
            std::filesystem::remove(spec.out / (stem + ".reactive.json"), ec);
            return true;
          }
          g.reactive = stem + ".reactive.json";
          g.replayed = stem + ".replayed.json";
          g.repro = planner_command(spec) + " --scenario " +
                    shell_quote((spec.out / g.reactive).string());
          return check_group(spec, *tracks[c.map_index], config, marks.at(gi), g, &halt);
        };
        if (!cut_and_check(spec.warm_up_all) && g.nondeterministic.empty() && !halt) {
          (void)cut_and_check(true);
          if (g.cut_error.empty()) {
            g.warm_up = "all (" + fixed_text(spec.warm_up_s, 0) + " s did not bring it in step)";
          }
        }
      }
      if (!new_groups.empty()) write_reports();
      if (static_cast<int>(out.failures.size()) >= spec.failures) break;
    }
  } catch (const std::exception& e) {
    failure = e.what();
  } catch (...) {
    failure = "an unknown error";
  }
  enough = true;
  halt = true;
  for (auto& t : pool) {
    if (t.joinable()) t.join();
  }
  // Runs past the last one taken are not part of the hunt; nor is a run an error cut short.
  remove_run_files(spec.out / kRunsDir);
  out.interrupted = stop && stop->load() && static_cast<int>(out.failures.size()) < spec.failures &&
                    taken < shard_runs;
  if (!failure.empty()) {
    // What was found is kept (hunt.json says the hunt stopped on an error; a shard that did is
    // not finished), then the reason goes up to the command line.
    out.error = failure;
    if (out.shard) out.shard->finished = false;
    out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    std::string kept;
    try {
      write_file_atomic(spec.out / "hunt.json", json_text(hunt_json(spec, out), 2) + "\n");
      kept = std::to_string(out.failures.size()) + " failure" +
             (out.failures.size() == 1 ? "" : "s") + " found before it kept in " +
             (spec.out / "hunt.json").string();
    } catch (const std::exception& e) {
      kept = "what was found could not be kept either (" + std::string(e.what()) + ")";
    }
    try {
      write_file_atomic(spec.out / "hunt.md", hunt_markdown(spec, out));
    } catch (const std::exception&) {  // hunt.json holds the outcome; the reason is said
    }
    throw std::runtime_error("hunt stopped: " + failure + "; " + kept);
  }
  if (out.shard) out.shard->finished = !out.interrupted;
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

namespace {

// One shard's hunt.json, read for merge_hunt.
struct HuntShard {
  std::filesystem::path dir;
  json report;
  std::vector<HuntFailure> failures;
  std::map<std::string, HuntGroup> groups;  ///< by situation
};

HuntShard read_hunt_shard(const std::filesystem::path& dir) {
  HuntShard h;
  h.dir = dir;
  const std::filesystem::path file = dir / "hunt.json";
  try {
    h.report = read_json_file(file);
    for (const json& f : h.report.at("failures")) {
      HuntFailure x;
      x.run = f.at("run").get<std::size_t>();
      x.seed = f.at("seed").get<std::uint64_t>();
      x.traffic = f.at("traffic").get<std::string>();
      x.map = f.at("map").get<std::string>();
      x.t_s = f.at("t_s").get<double>();
      x.what = f.at("what").get<std::string>();
      x.situation = f.at("situation").get<std::string>();
      x.replay = f.at("replay").get<std::string>();
      x.rerun = f.at("rerun").get<std::string>();
      h.failures.push_back(std::move(x));
    }
    for (const json& g : h.report.at("groups")) {
      HuntGroup x;
      x.situation = g.at("situation").get<std::string>();
      x.reactive = g.at("reactive").get<std::string>();
      x.replayed = g.at("replayed").get<std::string>();
      x.cut_error = g.at("cut_error").get<std::string>();
      if (g.contains("reproduces")) {
        x.reproduces_reactive = g.at("reproduces").at("reactive").get<std::string>();
        x.reproduces_replayed = g.at("reproduces").at("replayed").get<std::string>();
        x.reproduced = g.at("reproduced").get<bool>();
        if (g.contains("warm_up") && g.at("warm_up").is_string())
          x.warm_up = g.at("warm_up").get<std::string>();
        if (g.at("nondeterministic").is_string())
          x.nondeterministic = g.at("nondeterministic").get<std::string>();
      }
      h.groups.emplace(x.situation, std::move(x));
    }
    (void)h.report.at("shard").at("sweep");
  } catch (const std::exception& e) {
    throw UsageError("merge: " + file.string() + " is not the report of a hunt shard (" + e.what() +
                     "); run each shard with hunt --shard I/N");
  }
  return h;
}

// Copies `rel` of `from` to the same place under `to` (the merge's replays and scenarios).
void copy_into(const std::filesystem::path& from, const std::filesystem::path& to,
               const std::string& rel) {
  if (rel.empty()) return;
  std::error_code ec;
  const std::filesystem::path dest = to / rel;
  std::filesystem::create_directories(dest.parent_path(), ec);
  if (!std::filesystem::copy_file(from / rel, dest,
                                  std::filesystem::copy_options::overwrite_existing, ec) ||
      ec) {
    throw std::runtime_error(dest.string() + ": cannot copy " + (from / rel).string() + " here (" +
                             ec.message() + ")");
  }
}

// Copies a cut scenario of a shard (`rel` of `from`) into `to`, naming the replay it was cut
// from where the merge put that replay: the merged folder stands alone.
void copy_scenario(const std::filesystem::path& from, const std::filesystem::path& to,
                   const std::string& rel) {
  if (rel.empty()) return;
  nlohmann::ordered_json j;
  try {
    const std::string text = read_file(from / rel, kMaxJsonFileBytes);
    core::require_json_depth(text, (from / rel).string());
    j = nlohmann::ordered_json::parse(text);
  } catch (const std::exception& e) {  // unreadable, too deep, or not JSON
    throw UsageError("merge: " + (from / rel).string() + " is not a scenario (" + e.what() + ")");
  }
  if (j.contains("cut") && j["cut"].contains("from") && j["cut"]["from"].contains("replay")) {
    const std::filesystem::path replay = j["cut"]["from"]["replay"].get<std::string>();
    j["cut"]["from"]["replay"] = (to / "replays" / replay.filename()).string();
  }
  std::error_code ec;
  std::filesystem::create_directories((to / rel).parent_path(), ec);
  write_file_atomic(to / rel, json_text(j, 2) + "\n");
}

}  // namespace

HuntOutcome merge_hunt(const std::vector<std::filesystem::path>& dirs,
                       const std::filesystem::path& out) {
  if (dirs.empty()) throw UsageError("merge: name the hunt folders to join");
  std::vector<HuntShard> shards;
  for (const auto& dir : dirs) shards.push_back(read_hunt_shard(dir));
  const json& first = shards.front().report["shard"];
  const json sweep = first["sweep"];
  const int count = first["count"].get<int>();
  std::set<int> seen;
  for (const HuntShard& h : shards) {
    const json& sh = h.report["shard"];
    if (same_file(h.dir, out)) {
      throw UsageError("merge: --out " + out.string() + " is one of the folders being joined (" +
                       h.dir.string() + "); merge into a new folder");
    }
    if (sh["sweep"] != sweep) {
      throw UsageError("merge: " + h.dir.string() + " is a shard of another hunt than " +
                       shards.front().dir.string() +
                       " (policy, minutes, failures, budget, traffic, maps, seeds or parameters "
                       "differ)");
    }
    if (sh["revision"] != first["revision"]) {
      throw UsageError("merge: the shards come from different builds of overtake: " +
                       first["revision"].get<std::string>() + " (in " +
                       shards.front().dir.string() + ") and " + sh["revision"].get<std::string>() +
                       " (in " + h.dir.string() + "); run every shard with the same binary");
    }
    const int index = sh["index"].get<int>();
    if (!seen.insert(index).second) {
      throw UsageError("merge: shard " + std::to_string(index) + " of " + std::to_string(count) +
                       " appears twice (" + h.dir.string() + ")");
    }
    if (!sh["finished"].get<bool>()) {
      throw UsageError("merge: " + h.dir.string() + " holds an unfinished shard (shard " +
                       std::to_string(index) + " was interrupted); run it again");
    }
  }
  if (static_cast<int>(seen.size()) != count) {
    throw UsageError("merge: the folders hold " + std::to_string(seen.size()) + " of the hunt's " +
                     std::to_string(count) + " shards; a shard is missing");
  }
  if (std::filesystem::exists(out / "hunt.json")) {
    throw UsageError("merge: --out " + out.string() +
                     " already holds a hunt; merge into a new "
                     "folder");
  }
  check_hunt_out(out, false, "merge: --out: ", "move it away, or merge into a new folder");

  // The first `failures` failures in run order (a shard keeps a run's failures in order).
  struct Found {
    const HuntShard* from;
    const HuntFailure* failure;
  };
  std::vector<Found> all;
  for (const HuntShard& h : shards) {
    for (const HuntFailure& f : h.failures) all.push_back({&h, &f});
  }
  std::stable_sort(all.begin(), all.end(),
                   [](const Found& a, const Found& b) { return a.failure->run < b.failure->run; });
  const auto wanted = sweep["failures"].get<std::size_t>();
  const auto max_runs = first["max_runs"].get<std::size_t>();
  if (all.size() > wanted) all.resize(wanted);
  // The runs one hunt would have taken: up to the run of the last failure it kept, or all.
  const std::size_t last_run = all.size() == wanted ? all.back().failure->run : max_runs - 1;

  HuntOutcome o;
  for (const HuntShard& h : shards) {
    for (const json& r : h.report["shard"]["run_seconds"]) {
      if (r[0].get<std::size_t>() > last_run) continue;
      ++o.runs;
      o.simulated_s += r[1].get<double>();
    }
    o.wall_s = std::max(o.wall_s, h.report["timing"].value("wall_s", 0.0));
  }
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) {
    throw std::runtime_error(out.string() + ": cannot create the output folder (" + ec.message() +
                             ")");
  }
  HuntSpec spec;
  spec.policy = sweep["policy"].get<std::string>();
  spec.minutes = sweep["minutes"].get<double>();
  std::map<std::string, std::size_t> group_of;
  for (const Found& f : all) {
    copy_into(f.from->dir, out, f.failure->replay);
    const std::size_t index = o.failures.size();
    o.failures.push_back(*f.failure);
    auto [it, is_new] = group_of.emplace(f.failure->situation, o.groups.size());
    if (is_new) {
      // The shard's group of this situation began with this failure: none came before it.
      const auto g = f.from->groups.find(f.failure->situation);
      if (g == f.from->groups.end()) {
        throw UsageError("merge: " + f.from->dir.string() + "/hunt.json lists a failure in '" +
                         f.failure->situation + "' but no group of it");
      }
      HuntGroup group = g->second;
      group.failures.clear();
      copy_scenario(f.from->dir, out, group.reactive);
      copy_scenario(f.from->dir, out, group.replayed);
      group.repro = group.reactive.empty()
                        ? f.failure->rerun
                        : planner_command_line(
                              call_from_description(spec.policy, sweep.value("planner", json()))) +
                              " --scenario " + shell_quote((out / group.reactive).string());
      o.groups.push_back(std::move(group));
    }
    o.groups[it->second].failures.push_back(index);
  }
  write_file_atomic(out / "hunt.json", json_text(hunt_json(spec, o), 2) + "\n");
  write_file_atomic(out / "hunt.md", hunt_markdown(spec, o));
  return o;
}

}  // namespace overtake::app

namespace overtake::app {
namespace {

// A shard's hunt.json, or null while there is none that can be read.
json shard_report(const std::filesystem::path& shard) {
  try {
    return read_json_file(shard / "hunt.json");
  } catch (const std::exception&) {
    return nullptr;
  }
}

// A hunt as a Slurm array: task I hunts slice I (starting over when submitted again: the same
// runs find the same failures); a shard is finished when its hunt.json says so; the shards
// merge as `hunt merge`.
SlurmArray hunt_array(const HuntSpec& spec, std::vector<std::string> args, bool resume,
                      bool quiet) {
  namespace fs = std::filesystem;
  SlurmArray a = slurm_array_here("hunt", spec.out);
  if (fs::exists(a.out / "hunt.json")) {
    throw UsageError("--out: " + a.out.string() +
                     " already holds a hunt (merged, or a local hunt); choose another --out");
  }
  // The shards merge into --out at the end: what the merge would refuse is refused now.
  check_hunt_out(a.out, false, "--out: ", "move it away, or choose another --out");
  a.args = std::move(args);
  // A task submitted again starts its shard over, in the array's own folder.
  a.task_flags = {"--force", "--quiet"};
  a.runs = hunt_max_runs(spec);
  a.resume = resume;
  a.quiet = quiet;
  a.shard_state = [](const fs::path& shard, int) {
    SlurmShardState st;
    const json j = shard_report(shard);
    if (j.is_object()) {
      st.finished = j.contains("shard") && j["shard"].value("finished", false);
      st.so_far = std::to_string(j.value("runs", 0)) + " runs and " +
                  std::to_string(j.value("failures", json::array()).size()) + " failures";
    }
    return st;
  };
  a.progress = [](const std::vector<fs::path>& shards) {
    std::size_t runs = 0, failures = 0;
    for (const auto& shard : shards) {
      const json j = shard_report(shard);
      if (!j.is_object()) continue;
      runs += j.value("runs", std::size_t{0});
      failures += j.value("failures", json::array()).size();
    }
    return std::to_string(runs) + " runs, " + std::to_string(failures) + " failures found";
  };
  const fs::path out = a.out;
  a.merge = [out, quiet](const std::vector<fs::path>& shards, double wall_s, int resubmitted) {
    (void)merge_hunt(shards, out);
    if (!quiet) {
      std::cout << read_file(out / "hunt.md");
      std::printf("%zu Slurm tasks (%d submitted again) in %.1f s\n", shards.size(), resubmitted,
                  wall_s);
      std::cout << "written: " << out.string() << "/{hunt.md,hunt.json,replays,scenarios}\n";
    }
    return kExitOk;
  };
  return a;
}

}  // namespace

Subcommand register_hunt(CLI::App& app) {
  struct State {
    HuntSpec spec;
    PlannerFlags planners;
    std::string maps, traffic = "faithful,calm", find = "collisions", config, out = "hunt-out";
    CLI::Option* policy_opt = nullptr;
    bool quiet = false;
    bool resume = false;
    std::string shard;
    SlurmOptions slurm;
    std::vector<std::string> merge_dirs;
    std::string merge_out;
    std::string warm_up = fixed_text(kDefaultWarmUpS, 0);
  };
  auto st = std::make_shared<State>();
  st->spec.jobs = static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
  auto* cmd = app.add_subcommand(
      "hunt",
      "Drive one planner over seeds, maps and traffic profiles in parallel until it has failed\n"
      "--failures times or --budget-hours of simulation are spent. For each distinct failure\n"
      "(grouped by kind and situation) it keeps the replay, cuts a scenario with reactive and\n"
      "one with replayed traffic, and prints the command that reproduces it (hunt.md,\n"
      "hunt.json in --out). Ctrl-C keeps what was found (docs/scenarios.md).\n"
      "Exit status: 0; 130 when interrupted; 1 when a run, a replay or a report cannot be\n"
      "made (the reason is printed; what was found is kept in hunt.json); 2 for bad flags.");
  st->policy_opt =
      cmd->add_option("--policy", st->spec.policy, policy_help())->capture_default_str();
  add_planner_flags(*cmd, st->planners, PlannerFlagSet::all);
  cmd->add_option("--failures,-n", st->spec.failures, "Stop after this many failures")
      ->capture_default_str();
  cmd->add_option("--budget-hours", st->spec.budget_hours,
                  "... or after this many simulated hours (more than 0, at most 100000)")
      ->capture_default_str();
  cmd->add_option("--find", st->find,
                  "What counts as a failure: collisions (each contact with a car once, however\n"
                  "long), at-fault (those contacts that were the ego's fault) or incidents (any\n"
                  "of the rubric's; one counted again each second it lasts is one failure)")
      ->capture_default_str();
  cmd->add_option("--first-seed", st->spec.first_seed, "Seeds go up from this one")
      ->check(seed_validator())
      ->capture_default_str();
  cmd->add_option("--maps", st->maps,
                  "Comma-separated map files to drive on, each once (\"default\" for the\n"
                  "built-in track; default: the built-in track)");
  cmd->add_option("--traffic", st->traffic, "Comma-separated traffic profiles, each once")
      ->capture_default_str();
  cmd->add_option("--minutes", st->spec.minutes, "Simulated minutes per run")
      ->capture_default_str();
  cmd->add_option("--before", st->spec.before_s,
                  "The cut scenarios start this long before (0-3600 s, as `overtake cut`)")
      ->capture_default_str();
  cmd->add_option("--after", st->spec.after_s, "... and end this long after the failure (0-3600 s)")
      ->capture_default_str();
  cmd->add_option("--warm-up", st->warm_up,
                  "A failure of a planner from outside (a program, a plugin, Python) is cut with\n"
                  "this many seconds of what the planner was told before the scenario, played\n"
                  "to it first so that it comes in step (`all`: from the run's first cycle; 0:\n"
                  "none), as `overtake cut --warm-up`")
      ->capture_default_str();
  cmd->add_option("--config", st->config, "JSON parameter overrides")->check(CLI::ExistingFile);
  cmd->add_option("--jobs,-j", st->spec.jobs, "Runs in parallel (default: all cores)")
      ->capture_default_str();
  cmd->add_option("--out,-o", st->out, "Output folder")->capture_default_str();
  cmd->add_flag("--force", st->spec.force,
                "Write into --out even when it holds a hunt (hunt.json, hunt.md) or files in\n"
                "its replays/ or scenarios/: the new hunt's files replace those of the same names");
  cmd->add_flag("--quiet,-q", st->quiet, "No progress line or table");
  cmd->add_option("--shard", st->shard,
                  "Hunt only slice I of N (e.g. 3/8) of the runs, until this slice has found\n"
                  "--failures; `overtake hunt merge` of all N finds what one hunt would");
  add_slurm_flags(*cmd, st->slurm, "hunt");
  cmd->add_flag("--resume", st->resume,
                "With --slurm: take up the array submitted into --out before (follow it,\n"
                "submit again what did not finish, merge)");
  auto* merge = cmd->add_subcommand(
      "merge", "Join the folders of the shards of one hunt (--shard I/N) into --out.");
  merge->add_option("dirs", st->merge_dirs, "Shard folders")
      ->required()
      ->check(CLI::ExistingDirectory);
  merge->add_option("--out,-o", st->merge_out, "Folder for the joined hunt")->required();
  return {
      cmd, [st, cmd, merge] {
        if (merge->parsed()) {
          const std::filesystem::path out = st->merge_out;
          (void)merge_hunt(
              std::vector<std::filesystem::path>(st->merge_dirs.begin(), st->merge_dirs.end()),
              out);
          std::cout << read_file(out / "hunt.md") << "written: " << st->merge_out
                    << "/{hunt.md,hunt.json,replays,scenarios}\n";
          return kExitOk;
        }
        const bool on_slurm = slurm_requested(*cmd);
        if (st->resume && !on_slurm) throw UsageError("--resume goes with --slurm TASKS");
        if (on_slurm && !st->shard.empty())
          throw UsageError("--slurm makes the shards itself; --shard is for arrays of your own");
        if (on_slurm && st->spec.force)
          throw UsageError(
              "--force: a hunt on Slurm merges into --out, which must not hold a "
              "hunt; choose another --out");
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
        parse_warm_up(st->warm_up, spec.warm_up_s, spec.warm_up_all);
        if (!st->config.empty()) spec.config = st->config;
        spec.out = st->out;
        if (!st->shard.empty())
          std::tie(spec.shard_index, spec.shard_count) = parse_shard(st->shard);
        if (on_slurm) {
          check_hunt_spec(spec);
          check_programs_for_slurm(*spec.planners, st->planners.network);
          const SlurmArray array = hunt_array(
              spec, task_arguments(*cmd, {"out", "jobs", "resume", "quiet", "shard", "force"}),
              st->resume, st->quiet);
          const InterruptScope interrupt;
          return run_slurm_array(array, st->slurm, &InterruptScope::flag());
        }
        const bool draw = !st->quiet && stderr_is_terminal();
        HuntOutcome o;
        {
          const InterruptScope interrupt;
          const auto end_line = [&] {
            if (draw) std::fprintf(stderr, "\n");
          };
          try {
            o = run_hunt(spec, &InterruptScope::flag(), [&](const HuntProgress& p) {
              if (!draw) return;
              const double rate = p.wall_s > 0 ? (p.simulated_s / 3600.0) / (p.wall_s / 60.0) : 0;
              const double left_s =
                  p.simulated_s > 0 ? p.wall_s * (p.budget_s - p.simulated_s) / p.simulated_s : 0;
              std::fprintf(stderr,
                           "\r  hunt: %zu runs, %.1f of %.1f simulated h, %zu failures in %zu "
                           "situations, %.1f sim-h/min, at most %.0f s to go   ",
                           p.runs, p.simulated_s / 3600.0, p.budget_s / 3600.0, p.failures,
                           p.groups, rate, left_s);
              std::fflush(stderr);
            });
          } catch (...) {
            end_line();
            throw;
          }
          end_line();
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
