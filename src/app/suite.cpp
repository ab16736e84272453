#include "overtake/app/suite.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <sstream>
#include <string_view>
#include <thread>

#include "overtake/app/cli.hpp"
#include "overtake/app/commands.hpp"
#include "overtake/app/config.hpp"
#include "overtake/app/io.hpp"
#include "overtake/app/report.hpp"
#include "overtake/app/scenario_file.hpp"
#include "overtake/core/road.hpp"

namespace overtake::app {
namespace {

using nlohmann::json;

constexpr int kMaxJobs = 256;

/// Follows the ego's lane, and the distance it drove in the lead-in, through the frames of a
/// run.
class TraceWatch final : public sim::RunObserver {
 public:
  TraceWatch(const core::RoadParams& road, double lead_in_s) : road_(road), lead_in_s_(lead_in_s) {
    trace.lane_reached_s.assign(static_cast<std::size_t>(road.lane_count), std::nullopt);
  }
  void on_frame(const sim::Frame& frame, std::span<const sim::Incident> /*new*/) override {
    const double t = static_cast<double>(frame.step) * step_s;
    if (first_) {
      trace.start_s = t;
      first_ = false;
    }
    // The judged part starts at the lead-in's end (the first frame without one).
    if (t - trace.start_s <= lead_in_s_ + 1e-9) trace.lead_in_distance_m = frame.distance_m;
    // In a lane: the ego's d within it (its centre within half a lane).
    const int lane = core::lane_of(frame.d_m, road_);
    if (lane >= 0 && lane < road_.lane_count) {
      auto& reached = trace.lane_reached_s[static_cast<std::size_t>(lane)];
      if (!reached) reached = t - trace.start_s;
    }
  }
  void on_path(std::span<const core::Vec2> /*path*/) override {}
  ScenarioTrace trace;
  double step_s = 0.02;

 private:
  core::RoadParams road_;
  double lead_in_s_ = 0.0;
  bool first_ = true;
};

/// Refuses an --out that is the scenarios folder (its suite.json would be read as a scenario
/// by the next run), or that holds a suite.md or suite.json overtake did not write.
void check_out(const SuiteSpec& spec) {
  if (!spec.out) return;
  const std::filesystem::path& out = *spec.out;
  if (same_file(out, spec.dir)) {
    throw UsageError("--out: " + out.string() + " is the scenarios folder; the suite's " +
                     kSuiteVerdictsFile +
                     " would be read as a scenario by the next run: write to " +
                     "another folder (a subfolder of it is fine)");
  }
  const std::pair<const char*, bool (*)(const std::filesystem::path&)> outputs[] = {
      {kSuiteTableFile, is_suite_table}, {kSuiteVerdictsFile, is_suite_verdicts}};
  for (const auto& [name, ours] : outputs) {
    const std::filesystem::path file = out / name;
    std::error_code ec;
    const auto st = std::filesystem::symlink_status(file, ec);
    if (ec || !std::filesystem::exists(st)) continue;
    if (!std::filesystem::is_regular_file(st) || !ours(file)) {
      throw UsageError("--out: " + file.string() +
                       " was not written by an overtake suite and would be replaced; move it "
                       "away, or give another --out");
    }
  }
  // Its replays and logs are a suite's when its verdicts are there: otherwise a replays/ or
  // logs/ folder with anything in it is someone else's, and a failed run's files would be
  // written over theirs.
  std::error_code ec;
  if (std::filesystem::exists(out / kSuiteVerdictsFile, ec)) return;
  for (const char* folder : {"replays", "logs"}) {
    const std::filesystem::path dir = out / folder;
    if (std::filesystem::exists(std::filesystem::symlink_status(dir, ec)) &&
        !std::filesystem::is_empty(dir, ec)) {
      throw UsageError("--out: " + dir.string() +
                       " holds files no overtake suite wrote there (no suite.json beside it), "
                       "which a failed run's files would replace; move it away, or give "
                       "another --out");
    }
  }
}

std::string incident_text(const sim::Incident& i) {
  std::string text = std::string(sim::to_string(i.type));
  if (i.collision) {
    text += std::string(" ") + std::string(sim::to_string(i.collision->kind));
  }
  return text + " at t " + fixed_text(i.t_s, 2) + " s";
}

/// The incidents of the judged part.
std::vector<sim::Incident> judged_incidents(const sim::Scenario& sc, const sim::RunReport& r,
                                            const ScenarioTrace& trace) {
  const double from = trace.start_s + (sc.cut ? sc.cut->lead_in_s : 0.0) - 1e-9;
  std::vector<sim::Incident> out;
  for (const sim::Incident& i : r.incidents) {
    if (i.t_s >= from) out.push_back(i);
  }
  return out;
}

/// The collisions of the judged part, as contacts (one per car touched, however long).
std::vector<sim::Incident> judged_contacts(const sim::Scenario& sc, const sim::RunReport& r,
                                           const ScenarioTrace& trace) {
  const double from = trace.start_s + (sc.cut ? sc.cut->lead_in_s : 0.0) - 1e-9;
  std::vector<sim::Incident> out;
  for (std::size_t k = 0; k < r.contacts.size(); ++k) {
    if (r.contacts[k].t_s >= from)
      out.push_back(contact_incident(r.contacts[k], static_cast<int>(k)));
  }
  return out;
}

}  // namespace

std::vector<std::string> judge_scenario(const sim::Scenario& sc, const sim::RunReport& r,
                                        const ScenarioTrace& trace) {
  std::vector<std::string> fails;
  if (r.outcome.end == sim::RunEnd::planner_failed) {
    fails.push_back("the planner failed: " + r.outcome.reason);
  }
  const std::vector<sim::Incident> inc = judged_incidents(sc, r, trace);
  const std::vector<sim::Incident> contacts = judged_contacts(sc, r, trace);
  std::vector<const sim::Incident*> collisions, at_fault;
  for (const sim::Incident& i : contacts) {
    collisions.push_back(&i);
    if (i.collision->at_fault) at_fault.push_back(&i);
  }
  const auto limit = [&](const std::optional<int>& max, std::size_t got, const char* what,
                         const sim::Incident* first) {
    if (max && got > static_cast<std::size_t>(*max)) {
      fails.push_back(std::to_string(got) + " " + what + (got == 1 ? "" : "s") + " (at most " +
                      std::to_string(*max) + "); the first: " + incident_text(*first));
    }
  };
  sim::ScenarioExpect ex = sc.expect;
  if (!ex.any()) ex.max_at_fault_collisions = 0;
  limit(ex.max_at_fault_collisions, at_fault.size(), "at-fault collision",
        at_fault.empty() ? nullptr : at_fault.front());
  limit(ex.max_collisions, collisions.size(), "collision",
        collisions.empty() ? nullptr : collisions.front());
  limit(ex.max_incidents, inc.size(), "incident", inc.empty() ? nullptr : &inc.front());
  if (ex.reach_lane) {
    const auto lane = static_cast<std::size_t>(*ex.reach_lane);
    const auto& reached =
        lane < trace.lane_reached_s.size() ? trace.lane_reached_s[lane] : std::nullopt;
    if (!reached || *reached > ex.reach_lane_by_s + 1e-9) {
      fails.push_back("did not reach lane " + std::to_string(*ex.reach_lane) + " by t " +
                      fixed_text(ex.reach_lane_by_s, 1) + " s" +
                      (reached ? " (reached it at t " + fixed_text(*reached, 2) + " s)"
                               : std::string(" (never)")));
    }
  }
  const double lead_in_s = sc.cut ? sc.cut->lead_in_s : 0.0;
  const double judged_m = judged_distance_m(r, trace);
  if (ex.min_distance_m && judged_m < *ex.min_distance_m) {
    fails.push_back("drove " + fixed_text(judged_m, 1) + " m" +
                    (lead_in_s > 0.0 ? std::string(" after the lead-in") : std::string()) +
                    ", less than " + fixed_text(*ex.min_distance_m, 1) + " m");
  }
  // A run over before its lead-in was has nothing judged: it cannot pass.
  if (lead_in_s > 0.0 && r.duration_s + 1e-9 < lead_in_s &&
      r.outcome.end != sim::RunEnd::planner_failed) {
    fails.push_back("the run lasted " + fixed_text(r.duration_s, 2) + " s, within the lead-in (" +
                    fixed_text(lead_in_s, 2) + " s): nothing was judged");
  }
  return fails;
}

double judged_distance_m(const sim::RunReport& report, const ScenarioTrace& trace) {
  return std::max(0.0, report.distance_m - trace.lead_in_distance_m);
}

SuiteOutcome run_suite(const SuiteSpec& spec, const std::atomic<bool>* stop,
                       const std::function<void(std::size_t, std::size_t)>& progress) {
  if (spec.policies.empty()) throw UsageError("--policies: no policy given");
  check_unique_names(spec.policies, "--policies");
  if (spec.jobs < 1 || spec.jobs > kMaxJobs) {
    throw UsageError("--jobs must be between 1 and " + std::to_string(kMaxJobs));
  }
  std::error_code ec;
  if (!std::filesystem::is_directory(spec.dir, ec)) {
    throw UsageError("--scenarios: " + spec.dir.string() + " is not a folder");
  }
  check_out(spec);
  SuiteOutcome outcome;
  ScenarioFolder folder = list_scenario_folder(spec.dir);
  std::vector<std::filesystem::path> files = std::move(folder.files);
  outcome.skipped = std::move(folder.skipped);
  for (const auto& p : spec.policies) {
    DriveOptions o;
    o.policy = p;
    o.planners = spec.planners;
    validate_drive_options(o);
  }
  const Config config = load_config(spec.config);
  if (spec.out) {
    std::filesystem::create_directories(*spec.out / "replays", ec);
    if (ec) throw std::runtime_error(spec.out->string() + ": cannot create (" + ec.message() + ")");
  }

  struct Job {
    std::size_t file = 0;
    std::string policy;
  };
  std::vector<Job> jobs;
  for (std::size_t f = 0; f < files.size(); ++f) {
    for (const auto& p : spec.policies) jobs.push_back({f, p});
  }
  std::vector<std::optional<ScenarioVerdict>> verdicts(jobs.size());
  std::mutex mu;
  std::size_t done = 0;
  std::atomic<std::size_t> next{0};
  const auto wall0 = std::chrono::steady_clock::now();
  const auto stopping = [&] { return stop && stop->load(); };

  const auto run_one = [&](const Job& job) {
    ScenarioVerdict v;
    v.file = files[job.file].filename().string();
    v.policy = job.policy;
    if (const std::string why = unreadable_scenario(files[job.file]); !why.empty()) {
      v.failures.push_back("cannot read: " + why);
      return std::optional<ScenarioVerdict>(std::move(v));
    }
    try {
      DriveOptions o;
      o.scenario = files[job.file];
      o.minutes_from_scenario = true;
      o.policy = job.policy;
      o.planners = spec.planners;
      o.config = spec.config;
      if (spec.map) o.map = spec.map;
      const std::string stem = files[job.file].stem().string() + "-" + job.policy;
      if (spec.out) {
        o.record = *spec.out / "replays" / (stem + ".otr");
        o.checkpoint_every_s = 0.0;
        o.planner_log = *spec.out / "logs" / (stem + ".log");
      }
      DriveInputs in = load_drive_inputs(o);
      v.name = in.scenario->name;
      TraceWatch watch(config.road, in.scenario->cut ? in.scenario->cut->lead_in_s : 0.0);
      watch.step_s = in.config.world.step_s;
      in.options.watcher = &watch;
      const DriveResult r = drive_loaded(in, {}, stop);
      if (r.report.outcome.end == sim::RunEnd::stopped) return std::optional<ScenarioVerdict>();
      v.failures = judge_scenario(*in.scenario, r.report, watch.trace);
      v.incidents = static_cast<int>(judged_incidents(*in.scenario, r.report, watch.trace).size());
      for (const sim::Incident& i : judged_contacts(*in.scenario, r.report, watch.trace)) {
        ++v.collisions;
        if (i.collision->at_fault) ++v.at_fault_collisions;
      }
      v.distance_m = judged_distance_m(r.report, watch.trace);
      v.duration_s = r.report.duration_s;
      if (r.report.warm_up) v.warm_up = warm_up_text(*r.report.warm_up);
      v.pass = v.failures.empty();
      if (spec.out) {
        if (v.pass) {
          std::filesystem::remove(*o.record, ec);
        } else {
          v.replay = (std::filesystem::path("replays") / (stem + ".otr")).generic_string();
        }
      }
    } catch (const std::exception& e) {
      v.pass = false;
      v.failures.push_back(std::string("could not run: ") + e.what());
    }
    return std::optional<ScenarioVerdict>(std::move(v));
  };

  const auto worker = [&] {
    while (!stopping()) {
      const std::size_t i = next.fetch_add(1);
      if (i >= jobs.size()) return;
      std::optional<ScenarioVerdict> v = run_one(jobs[i]);
      std::lock_guard lock(mu);
      if (v) verdicts[i] = std::move(v);
      ++done;
      if (progress) progress(done, jobs.size());
    }
  };
  const int threads = std::min<int>(spec.jobs, static_cast<int>(jobs.size()));
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  for (auto& t : pool) t.join();

  for (auto& v : verdicts) {
    if (!v) {
      outcome.interrupted = true;
      continue;
    }
    (v->pass ? outcome.passed : outcome.failed) += 1;
    outcome.verdicts.push_back(std::move(*v));
  }
  outcome.interrupted = outcome.interrupted || stopping();
  outcome.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  if (spec.out) {
    // The verdicts first; a failure to write one file does not keep the other from being
    // written, nor the outcome from being returned (and its table printed).
    const std::pair<const char*, std::string> outputs[] = {
        {kSuiteVerdictsFile, json_text(suite_json(outcome), 2) + "\n"},
        {kSuiteTableFile, suite_table(outcome)}};
    for (const auto& [name, text] : outputs) {
      try {
        write_file_atomic(*spec.out / name, text);
      } catch (const std::exception& e) {
        outcome.write_errors.emplace_back(e.what());
      }
    }
  }
  return outcome;
}

}  // namespace overtake::app
