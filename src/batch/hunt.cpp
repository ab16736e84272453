#include "overtake/batch/hunt.hpp"

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

#include "hunt_internal.hpp"
#include "overtake/base/build_info.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/batch/merge.hpp"
#include "overtake/batch/policies.hpp"
#include "overtake/batch/pool.hpp"
#include "overtake/batch/shard.hpp"
#include "overtake/core/hash.hpp"
#include "overtake/core/road.hpp"
#include "overtake/core/text_check.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/replay/replay.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "overtake/scenarios/cut.hpp"
#include "overtake/scenarios/reproduce.hpp"

namespace overtake::batch {

using base::build_revision;
using base::check_unique_names;
using base::fixed_text;
using base::json_text;
using base::read_file;
using base::same_file;
using base::shell_quote;
using base::UsageError;
using base::write_file_atomic;
using hunt_detail::check_spec;
using hunt_detail::hunt_sweep;
using hunt_detail::load_hunt_tracks;
using hunt_detail::map_name;
using planners::call_from_description;
using planners::call_of;
using planners::planner_command_line;
using planners::PlannerEntry;
using planners::PlannerKind;
using run::Config;
using run::config_hash;
using run::contact_incident;
using run::drive_on;
using run::DriveOptions;
using run::DriveResult;
using run::kMaxJsonFileBytes;
using run::load_config;
using run::load_track;
using run::read_json_file;
using run::Track;
using run::validate_drive_options;
using scenarios::check_cut_window;
using scenarios::check_reproduction;
using scenarios::cut_replay;
using scenarios::CutOptions;
using scenarios::drives_differ;
using scenarios::FailureMark;
using scenarios::ReproCheck;
namespace {

using nlohmann::json;

/// Hex digits of a map's name's hash that tell apart maps whose slugs are the same.
constexpr std::size_t kMapTagHashDigits = 8;
/// The folder of the runs in progress (their replays until a run is taken).
constexpr const char* kRunsDir = "runs";
/// Below this the ego counts as standing, below the next as slow.
constexpr double kStandingMps = 0.5;
constexpr double kSlowMps = 10.0;
/// Further than this from its lane's centre, the ego is between lanes.
constexpr double kBetweenLanesM = 1.0;
/// An incident of the same type (and car) within this of the last is a repeat of it.
constexpr double kRepeatS = 1.5;

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
    text += " " + run::collision_text(*i.collision);
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
  const std::uint64_t seed =
      spec.seeds.empty() ? spec.first_seed + k / per_seed : spec.seeds.at(k / per_seed);
  return {seed, m, spec.maps[m], spec.traffic[within % spec.traffic.size()]};
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

std::string hunt_run_name(const HuntSpec& spec, std::size_t run) {
  const Combo c = combo_of(spec, run);
  return slug(spec.policy + "-" + map_tags(spec.maps)[c.map_index] + "-" + c.traffic + "-seed" +
              std::to_string(c.seed));
}

namespace {

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

namespace {

// What a hunt carries while it takes its runs in order, on the calling thread.
struct Hunt {
  Hunt(const HuntSpec& spec_in, const Config& config_in,
       const std::vector<std::shared_ptr<const Track>>& tracks_in, const std::atomic<bool>* stop_in)
      : spec(spec_in), config(config_in), tracks(tracks_in), stop(stop_in) {}

  const HuntSpec& spec;
  const Config& config;
  const std::vector<std::shared_ptr<const Track>>& tracks;
  const std::atomic<bool>* stop;  // the user's: also ends a group's checks at once
  std::chrono::steady_clock::time_point wall0 = std::chrono::steady_clock::now();
  HuntOutcome out;
  HuntProgress prog;
  std::map<std::string, std::size_t> group_of;
  std::size_t taken = 0;  // runs taken in order (an interrupted one too)

  [[nodiscard]] bool stopped() const { return stop && stop->load(); }
};

// Creates the hunt's folders in an --out it may write into.
void open_hunt_out(const HuntSpec& spec) {
  check_hunt_out(spec.out, spec.force,
                 "--out: ", "move it away, choose another --out, or give --force to replace it");
  std::error_code ec;
  for (const char* sub : {kRunsDir, "replays", "scenarios", "logs"}) {
    std::filesystem::create_directories(spec.out / sub, ec);
    if (ec)
      throw std::runtime_error((spec.out / sub).string() + ": cannot create (" + ec.message() +
                               ")");
  }
}

// Run k of the hunt, driven with its replay recorded into runs/. Throws "run K: why".
RunResult drive_hunt_run(const HuntSpec& spec, const Config& config,
                         const std::vector<std::shared_ptr<const Track>>& tracks, std::size_t k,
                         const std::atomic<bool>* halt) {
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
    const DriveResult r = drive_on(*tracks[c.map_index], config, o, {}, halt);
    res.report = r.report;
    res.stopped = r.report.outcome.end == sim::RunEnd::stopped;
  } catch (const std::exception& e) {
    throw std::runtime_error("run " + std::to_string(k) + ": " + e.what());
  }
  return res;
}

// The failures of a run, at most `room` of them: one per contact (a collision) or per episode
// (another incident): the referee counts a contact, a speeding or a straddle again each
// second it lasts; those repeats are the same failure.
std::vector<sim::Incident> failures_in(const HuntSpec& spec, const sim::RunReport& report,
                                       std::size_t room) {
  std::vector<sim::Incident> found;
  if (spec.target != HuntTarget::incidents) {
    for (std::size_t n = 0; n < report.contacts.size(); ++n) {
      const sim::Contact& contact = report.contacts[n];
      if (spec.target == HuntTarget::at_fault && !contact.collision.at_fault) continue;
      if (found.size() < room) found.push_back(contact_incident(contact, static_cast<int>(n)));
    }
    return found;
  }
  std::map<int, double> last_seen;  // type -> time of its last count
  std::set<int> contacts_seen;
  for (const sim::Incident& i : report.incidents) {
    bool repeat = false;
    if (i.type == sim::IncidentType::collision && i.contact >= 0) {
      repeat = !contacts_seen.insert(i.contact).second;
    } else {
      const auto it = last_seen.find(static_cast<int>(i.type));
      repeat = it != last_seen.end() && i.t_s - it->second <= kRepeatS;
      last_seen[static_cast<int>(i.type)] = i.t_s;
    }
    if (spec.incident_type && i.type != *spec.incident_type) continue;
    if (!repeat && found.size() < room) found.push_back(i);
  }
  return found;
}

// The outcome (hunt.json) first: a hunt.md that cannot be written loses nothing found.
void write_reports(Hunt& h) {
  h.out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - h.wall0).count();
  write_file_atomic(h.spec.out / "hunt.json", json_text(hunt_json(h.spec, h.out), 2) + "\n");
  write_file_atomic(h.spec.out / "hunt.md", hunt_markdown(h.spec, h.out));
}

// A failure of run k (an incident, or the planner's failure when `i` is null).
HuntFailure failure_of(const Hunt& h, std::size_t k, const sim::Incident* i, const RunResult& res,
                       const replay::Replay& r) {
  const Combo c = combo_of(h.spec, k);
  HuntFailure f;
  f.run = k;
  f.seed = c.seed;
  f.traffic = c.traffic;
  f.map = map_name(c.map);
  if (i) {
    f.t_s = i->t_s;
    f.what = what_of(*i);
    f.situation = situation_of(*i, c.traffic, r, h.config.road);
  } else {
    f.t_s = res.report.outcome.t_s;
    f.what = "the planner failed: " + res.report.outcome.reason.substr(0, 200);
    f.situation = "the planner failed, " + c.traffic + " traffic";
  }
  f.replay =
      (std::filesystem::path("replays") / (hunt_run_name(h.spec, k) + ".otr")).generic_string();
  f.rerun = rerun_command(h.spec, c, f.replay);
  return f;
}

// Adds a run's failures to the outcome, each in its situation's group; the groups that are
// new, with the failure each begins with (their scenarios are cut from it).
std::map<std::size_t, FailureMark> add_failures(Hunt& h, std::size_t k, const RunResult& res,
                                                const std::vector<const sim::Incident*>& failures,
                                                const replay::Replay& r) {
  std::map<std::size_t, FailureMark> marks;
  for (const sim::Incident* i : failures) {
    const HuntFailure f = failure_of(h, k, i, res, r);
    const std::size_t index = h.out.failures.size();
    h.out.failures.push_back(f);
    auto [it, is_new] = h.group_of.emplace(f.situation, h.out.groups.size());
    if (is_new) {
      HuntGroup g;
      g.situation = f.situation;
      g.repro = f.rerun;  // until its scenario is cut
      g.cut_error = "not cut yet";
      FailureMark mark;
      mark.t_s = f.t_s;
      if (i) mark.incident = *i;
      marks[h.out.groups.size()] = mark;
      h.out.groups.push_back(std::move(g));
    }
    h.out.groups[it->second].failures.push_back(index);
  }
  h.prog.failures = h.out.failures.size();
  h.prog.groups = h.out.groups.size();
  return marks;
}

// Cuts a group's two scenarios from the replay of its first failure (`all`: with every cycle
// from the run's first as the warm-up) and checks them; false when a warm-up did not bring the
// planner in step. A cut that fails is said in the group (cut_error); the failure stays, with
// its replay and the command that drives its run again.
bool cut_and_check(Hunt& h, HuntGroup& g, const FailureMark& mark,
                   const std::filesystem::path& kept, bool all) {
  const HuntFailure& f = h.out.failures[g.failures.front()];
  const Combo c = combo_of(h.spec, f.run);
  const std::string stem =
      "scenarios/" + slug(hunt_run_name(h.spec, f.run) + "-t" + fixed_text(f.t_s, 2));
  g.cut_error.clear();
  for (const bool replayed : {false, true}) {
    CutOptions co;
    co.replay = kept;
    co.at_s = f.t_s;
    co.before_s = h.spec.before_s;
    co.after_s = h.spec.after_s;
    co.replayed = replayed;
    co.warm_up_s = h.spec.warm_up_s;
    co.warm_up_all = all;
    co.config = h.spec.config;
    co.map = c.map;
    co.out = h.spec.out / (stem + (replayed ? ".replayed.json" : ".reactive.json"));
    co.description = "Found by overtake hunt: " + f.what + " of " + h.spec.policy + " at t " +
                     fixed_text(f.t_s, 2) + " s (" + f.situation + "; " + c.traffic +
                     " traffic, seed " + std::to_string(c.seed) + ", map " + f.map + ").";
    try {
      (void)cut_replay(co);
    } catch (const std::exception& e) {
      g.cut_error =
          (replayed ? "replayed traffic: " : "reactive traffic: ") + std::string(e.what());
      break;
    }
  }
  if (!g.cut_error.empty()) {
    std::error_code ec;
    std::filesystem::remove(h.spec.out / (stem + ".reactive.json"), ec);
    return true;
  }
  g.reactive = stem + ".reactive.json";
  g.replayed = stem + ".replayed.json";
  g.repro =
      planner_command(h.spec) + " --scenario " + shell_quote((h.spec.out / g.reactive).string());
  return check_group(h.spec, *h.tracks[c.map_index], h.config, mark, g, h.stop);
}

// Cuts a new group's scenarios with the hunt's warm-up; a planner from outside that does not
// come in step in it is cut again with every cycle from the run's first (its state is then
// the run's, if it is deterministic), and checked again.
void cut_group(Hunt& h, HuntGroup& g, const FailureMark& mark, const std::filesystem::path& kept) {
  if (!cut_and_check(h, g, mark, kept, h.spec.warm_up_all) && g.nondeterministic.empty() &&
      !h.stopped()) {
    (void)cut_and_check(h, g, mark, kept, true);
    if (g.cut_error.empty()) {
      g.warm_up = "all (" + fixed_text(h.spec.warm_up_s, 0) + " s did not bring it in step)";
    }
  }
}

// Takes run k, the next in order: counts it, keeps its failures (its replay, their groups,
// their scenarios). False when the hunt takes no more (the run was interrupted, or enough
// failures are found).
bool take_run(Hunt& h, std::size_t k, RunResult&& res) {
  ++h.taken;
  if (res.stopped) return false;  // interrupted mid-run: not a finished run
  ++h.out.runs;
  h.out.simulated_s += res.report.duration_s;
  if (h.out.shard) h.out.shard->run_seconds.emplace_back(k, res.report.duration_s);
  h.prog.runs = h.out.runs;
  h.prog.simulated_s = h.out.simulated_s;
  const auto wanted = static_cast<std::size_t>(h.spec.failures);
  // A planner that fails (stalls, crashes, sends what cannot be read) is a failure too.
  const bool planner_failed =
      res.report.outcome.end == sim::RunEnd::planner_failed && h.out.failures.size() < wanted;
  const std::vector<sim::Incident> found =
      failures_in(h.spec, res.report, wanted - std::min(wanted, h.out.failures.size()));
  std::error_code ec;
  if (found.empty() && !planner_failed) {
    std::filesystem::remove(res.replay, ec);
    return true;
  }
  const std::filesystem::path kept = h.spec.out / "replays" / (hunt_run_name(h.spec, k) + ".otr");
  std::filesystem::rename(res.replay, kept, ec);
  if (ec)
    throw std::runtime_error(kept.string() + ": cannot keep the replay (" + ec.message() + ")");
  const replay::Replay r = replay::read_replay(kept);
  std::vector<const sim::Incident*> failures;
  for (const sim::Incident& i : found) failures.push_back(&i);
  if (planner_failed) failures.push_back(nullptr);
  const std::map<std::size_t, FailureMark> marks = add_failures(h, k, res, failures, r);
  // The failures are written before their scenarios are cut: a cut that fails loses none.
  write_reports(h);
  for (const auto& [gi, mark] : marks) cut_group(h, h.out.groups[gi], mark, kept);
  if (!marks.empty()) write_reports(h);
  return h.out.failures.size() < wanted;
}

// A hunt stopped by an error: what was found is kept (hunt.json says the hunt stopped on an
// error; a shard that did is not finished), then the reason goes up to the command line.
[[noreturn]] void end_on_error(Hunt& h, const std::string& failure) {
  h.out.error = failure;
  if (h.out.shard) h.out.shard->finished = false;
  h.out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - h.wall0).count();
  std::string kept;
  try {
    write_file_atomic(h.spec.out / "hunt.json", json_text(hunt_json(h.spec, h.out), 2) + "\n");
    kept = std::to_string(h.out.failures.size()) + " failure" +
           (h.out.failures.size() == 1 ? "" : "s") + " found before it kept in " +
           (h.spec.out / "hunt.json").string();
  } catch (const std::exception& e) {
    kept = "what was found could not be kept either (" + std::string(e.what()) + ")";
  }
  try {
    write_file_atomic(h.spec.out / "hunt.md", hunt_markdown(h.spec, h.out));
  } catch (const std::exception&) {  // hunt.json holds the outcome; the reason is said
  }
  throw std::runtime_error("hunt stopped: " + failure + "; " + kept);
}

}  // namespace

HuntOutcome run_hunt(const HuntSpec& spec, const std::atomic<bool>* stop,
                     const std::function<void(const HuntProgress&)>& progress) {
  check_spec(spec);
  const Config config = load_config(spec.config);
  const std::vector<std::shared_ptr<const Track>> tracks = load_hunt_tracks(spec);
  open_hunt_out(spec);
  const std::size_t max_runs = hunt_max_runs(spec);
  const Shard shard = spec.shard();
  const std::size_t shard_runs = shard.size_of(max_runs);
  Hunt h(spec, config, tracks, stop);
  if (spec.shard_count > 1) {
    h.out.shard.emplace();
    h.out.shard->max_runs = max_runs;
    h.out.shard->sweep = hunt_sweep(spec, config);
    h.out.shard->revision = std::string(build_revision());
  }
  h.prog.budget_s = static_cast<double>(shard_runs) * spec.minutes * 60.0;
  PoolOptions pool{spec.jobs, stop, PoolOrder::by_index, {}};
  pool.tick = [&] {
    h.prog.wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - h.wall0).count();
    if (progress) progress(h.prog);
  };
  std::string failure;  // why the hunt stopped before its end, when something failed
  try {
    // Results are taken in run order, so the same options find the same failures whatever
    // the number of jobs.
    (void)run_pool<RunResult>(
        shard_runs, pool,
        [&](std::size_t j, const std::atomic<bool>* halt) {
          return drive_hunt_run(spec, config, tracks, shard.item(j), halt);
        },
        [&](std::size_t j, RunResult&& res) { return take_run(h, shard.item(j), std::move(res)); });
  } catch (const std::exception& e) {
    failure = e.what();
  }
  // Runs past the last one taken are not part of the hunt; nor is a run an error cut short.
  remove_run_files(spec.out / kRunsDir);
  h.out.interrupted = h.stopped() && static_cast<int>(h.out.failures.size()) < spec.failures &&
                      h.taken < shard_runs;
  if (!failure.empty()) end_on_error(h, failure);
  if (h.out.shard) h.out.shard->finished = !h.out.interrupted;
  write_reports(h);
  if (progress) {
    h.prog.wall_s = h.out.wall_s;
    progress(h.prog);
  }
  return h.out;
}

}  // namespace overtake::batch
