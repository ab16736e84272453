#include "overtake/batch/suite_run.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <iostream>
#include <mutex>
#include <thread>

#include <nlohmann/json.hpp>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/policies.hpp"
#include "overtake/batch/pool.hpp"
#include "overtake/core/road.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "overtake/run/scenario_file.hpp"
#include "overtake/scenarios/suite.hpp"

namespace overtake::batch {

using base::check_unique_names;
using base::json_text;
using base::same_file;
using base::UsageError;
using base::write_file_atomic;
using run::Config;
using run::drive_loaded;
using run::DriveInputs;
using run::DriveOptions;
using run::DriveResult;
using run::load_config;
using run::load_drive_inputs;
using run::warm_up_text;
using scenarios::is_suite_table;
using scenarios::is_suite_verdicts;
using scenarios::judge_scenario;
using scenarios::judged_contacts;
using scenarios::judged_distance_m;
using scenarios::judged_incidents;
using scenarios::kSuiteTableFile;
using scenarios::kSuiteVerdictsFile;
using scenarios::list_scenario_folder;
using scenarios::ScenarioFolder;
using scenarios::ScenarioTrace;
using scenarios::ScenarioVerdict;
using scenarios::suite_json;
using scenarios::suite_table;
using scenarios::SuiteOutcome;
using scenarios::unreadable_scenario;
namespace {

using nlohmann::json;

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

}  // namespace

namespace {

// One scenario file driven by one policy.
struct SuiteJob {
  std::size_t file = 0;
  std::string policy;
};

// The verdict of one scenario run (a file that cannot be read or run fails it); nullopt when
// it was interrupted.
std::optional<ScenarioVerdict> judge_run(const SuiteSpec& spec, const Config& config,
                                         const std::filesystem::path& file,
                                         const std::string& policy, const std::atomic<bool>* halt) {
  ScenarioVerdict v;
  v.file = file.filename().string();
  v.policy = policy;
  if (const std::string why = unreadable_scenario(file); !why.empty()) {
    v.failures.push_back("cannot read: " + why);
    return v;
  }
  try {
    DriveOptions o;
    o.scenario = file;
    o.minutes_from_scenario = true;
    o.policy = policy;
    o.planners = spec.planners;
    o.config = spec.config;
    if (spec.map) o.map = spec.map;
    const std::string stem = file.stem().string() + "-" + policy;
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
    const DriveResult r = drive_loaded(in, {}, halt);
    if (r.report.outcome.end == sim::RunEnd::stopped) return std::nullopt;
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
        std::error_code ec;
        std::filesystem::remove(*o.record, ec);
      } else {
        v.replay = (std::filesystem::path("replays") / (stem + ".otr")).generic_string();
      }
    }
  } catch (const std::exception& e) {
    v.pass = false;
    v.failures.push_back(std::string("could not run: ") + e.what());
  }
  return v;
}

// Writes suite.json and suite.md: the verdicts first; a failure to write one file does not
// keep the other from being written, nor the outcome from being returned (and its table
// printed).
void write_suite(const std::filesystem::path& out, SuiteOutcome& outcome) {
  const std::pair<const char*, std::string> outputs[] = {
      {kSuiteVerdictsFile, json_text(suite_json(outcome), 2) + "\n"},
      {kSuiteTableFile, suite_table(outcome)}};
  for (const auto& [name, text] : outputs) {
    try {
      write_file_atomic(out / name, text);
    } catch (const std::exception& e) {
      outcome.write_errors.emplace_back(e.what());
    }
  }
}

}  // namespace

SuiteOutcome run_suite(const SuiteSpec& spec, const std::atomic<bool>* stop,
                       const std::function<void(std::size_t, std::size_t)>& progress) {
  if (spec.policies.empty()) throw UsageError("--policies: no policy given");
  check_unique_names(spec.policies, "--policies");
  check_jobs(spec.jobs);
  std::error_code ec;
  if (!std::filesystem::is_directory(spec.dir, ec)) {
    throw UsageError("--scenarios: " + spec.dir.string() + " is not a folder");
  }
  check_out(spec);
  SuiteOutcome outcome;
  ScenarioFolder folder = list_scenario_folder(spec.dir);
  const std::vector<std::filesystem::path> files = std::move(folder.files);
  outcome.skipped = std::move(folder.skipped);
  check_policy_names(spec.policies, spec.planners);
  const Config config = load_config(spec.config);
  if (spec.out) {
    std::filesystem::create_directories(*spec.out / "replays", ec);
    if (ec) throw std::runtime_error(spec.out->string() + ": cannot create (" + ec.message() + ")");
  }
  std::vector<SuiteJob> jobs;
  for (std::size_t f = 0; f < files.size(); ++f) {
    for (const auto& p : spec.policies) jobs.push_back({f, p});
  }
  std::vector<std::optional<ScenarioVerdict>> verdicts(jobs.size());
  std::size_t done = 0;
  const auto wall0 = std::chrono::steady_clock::now();
  (void)run_pool<std::optional<ScenarioVerdict>>(
      jobs.size(), {spec.jobs, stop, PoolOrder::as_finished, {}},
      [&](std::size_t i, const std::atomic<bool>* halt) {
        return judge_run(spec, config, files[jobs[i].file], jobs[i].policy, halt);
      },
      [&](std::size_t i, std::optional<ScenarioVerdict>&& v) {
        verdicts[i] = std::move(v);
        if (progress) progress(++done, jobs.size());
        return true;
      });
  for (auto& v : verdicts) {
    if (!v) {
      outcome.interrupted = true;
      continue;
    }
    (v->pass ? outcome.passed : outcome.failed) += 1;
    outcome.verdicts.push_back(std::move(*v));
  }
  outcome.interrupted = outcome.interrupted || (stop && stop->load());
  outcome.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  if (spec.out) write_suite(*spec.out, outcome);
  return outcome;
}

int report_suite(const SuiteSpec& suite, const scenarios::SuiteOutcome& o, bool quiet) {
  for (const std::string& f : o.skipped) {
    std::cerr << "bench: skipped " << (suite.dir / f).string()
              << ": a suite's verdicts, not a scenario\n";
  }
  if (!quiet) {
    std::cout << scenarios::suite_table(o);
    if (suite.out && o.write_errors.empty()) {
      std::cout << "written: " << suite.out->string() << "/{suite.md,suite.json}\n";
    }
  }
  for (const std::string& e : o.write_errors) std::cerr << "bench: " << e << "\n";
  if (!o.write_errors.empty()) return base::kExitFailure;
  if (o.interrupted) {
    std::cerr << "bench: interrupted; " << o.verdicts.size() << " scenario runs judged\n";
    return base::kExitInterrupted;
  }
  return o.failed > 0 ? base::kExitFailure : base::kExitOk;
}

}  // namespace overtake::batch
