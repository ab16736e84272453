#include "overtake/scenarios/cut.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <sstream>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/core/hash.hpp"
#include "overtake/core/units.hpp"
#include "overtake/core/waypoint_frenet.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/replay/replay.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "overtake/run/scenario_file.hpp"
#include "overtake/sim/checkpoint.hpp"
#include "overtake/sim/recorded_traffic.hpp"
#include "overtake/sim/world.hpp"

namespace overtake::scenarios {

using base::fixed_text;
using base::json_text;
using base::same_file;
using base::shell_quote;
using base::UsageError;
using base::write_file_atomic;
using planners::call_from_description;
using planners::planner_command_line;
using planners::PlannerCall;
using run::collision_text;
using run::Config;
using run::config_hash;
using run::ConfigError;
using run::kBuiltinMapSource;
using run::kMaxBlobBytes;
using run::kMaxWarmUpBytes;
using run::load_config;
using run::load_track;
using run::pack_blob;
void check_cut_window(double before_s, double after_s, double lead_in_s) {
  for (const auto& [flag, value] : {std::pair<const char*, double>{"--before", before_s},
                                    {"--after", after_s},
                                    {"--lead-in", lead_in_s}}) {
    if (!std::isfinite(value) || value < 0.0 || value > kMaxCutWindowS) {
      std::ostringstream os;
      os << flag << " must be between 0 and " << kMaxCutWindowS << " s (got " << value << ")";
      throw UsageError(os.str());
    }
  }
  if (before_s + after_s < kMinCutJudgedS) {
    throw UsageError("--before " + fixed_text(before_s, 2) + " s and --after " +
                     fixed_text(after_s, 2) + " s leave " + fixed_text(before_s + after_s, 2) +
                     " s to judge; together they must make at least " +
                     fixed_text(kMinCutJudgedS, 0) + " s (the lead-in is not judged)");
  }
}

void parse_warm_up(const std::string& text, double& seconds, bool& all) {
  all = text == "all";
  seconds = 0.0;
  if (all) return;
  std::size_t used = 0;
  try {
    seconds = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(seconds) || seconds < 0.0 ||
      seconds > kMaxCutWindowS) {
    throw UsageError("--warm-up: '" + text + "' is neither a time from 0 to " +
                     fixed_text(kMaxCutWindowS, 0) + " s nor all");
  }
}

namespace {

using nlohmann::ordered_json;

constexpr double kEps = 1e-9;
/// A re-driven ego further than this from its recorded place (stored to the centimetre) has
/// not driven the same.
constexpr double kSameRunToleranceM = 0.011;
/// The incident a cut is named after: within this of the moment.
constexpr double kNearIncidentS = 1.0;
/// A recorded car this far outside the road is one waiting off it (parked).
constexpr double kParkedMarginM = 20.0;

void check_options(const CutOptions& o) {
  if (!std::isfinite(o.at_s) || o.at_s < 0.0) {
    throw UsageError("--at must be a time in seconds, at least 0");
  }
  check_cut_window(o.before_s, o.after_s, o.lead_in_s);
  if (o.out.empty()) throw UsageError("-o/--out: give the scenario file to write");
  if (same_file(o.out, o.replay)) {
    throw UsageError("-o/--out names the replay itself (" + o.out.string() + ")");
  }
}

/// The incident nearest `at_s` within kNearIncidentS (collisions first), as text.
std::string incident_near(const replay::Replay& r, double at_s) {
  const double step_s = r.header.step_s;
  const replay::ReplayIncident* best = nullptr;
  for (const replay::ReplayIncident& i : r.incidents) {
    const double t = static_cast<double>(i.step) * step_s;
    if (std::abs(t - at_s) > kNearIncidentS) continue;
    const bool collision = i.collision.has_value();
    const bool best_collision = best && best->collision.has_value();
    if (!best || (collision && !best_collision) ||
        (collision == best_collision &&
         std::abs(t - at_s) < std::abs(static_cast<double>(best->step) * step_s - at_s))) {
      best = &i;
    }
  }
  if (!best) return {};
  const auto type = static_cast<std::size_t>(best->type);
  std::string text = type < r.header.incident_types.size() ? r.header.incident_types[type]
                                                           : std::string("incident");
  if (best->collision) {
    text += " " + collision_text(*best->collision);
  }
  return text + " at t " + fixed_text(static_cast<double>(best->step) * step_s, 2) + " s";
}

/// Recorded frames as traffic bodies, steps [first, last] (for a run whose planner cannot be
/// driven on: positions to the centimetre, headings to 1e-4 rad, speeds to 1 cm/s).
sim::RecordedTraffic bodies_from_frames(const replay::Replay& r, long first, long last,
                                        const core::Map& map, const core::RoadParams& road) {
  const core::WaypointFrenet chords(map);
  const double width = core::road_width_m(road);
  sim::RecordedTraffic steps;
  std::vector<std::size_t> hint;
  for (const replay::ReplayFrame& f : r.frames) {
    if (f.step < first || f.step > last) continue;
    int count = 0;
    for (const sim::CarPose& c : f.cars) count = std::max(count, c.id + 1);
    std::vector<sim::TrafficCar> cars(static_cast<std::size_t>(count));
    hint.resize(cars.size(), 0);
    for (std::size_t k = 0; k < cars.size(); ++k) {
      cars[k].id = static_cast<int>(k);
      cars[k].parked = true;
    }
    for (const sim::CarPose& c : f.cars) {
      sim::TrafficCar& b = cars[static_cast<std::size_t>(c.id)];
      b.position = c.position;
      b.heading_rad = c.yaw_rad;
      b.speed_mps = c.speed_mps;
      b.reported_velocity_mps = c.speed_mps * core::Vec2{std::cos(c.yaw_rad), std::sin(c.yaw_rad)};
      std::size_t& h = hint[static_cast<std::size_t>(c.id)];
      h = chords.closest(c.position, h);
      b.closest_waypoint = h;
      b.map_frenet = chords.to_frenet(c.position, h);
      b.parked = b.map_frenet.d_m < -kParkedMarginM || b.map_frenet.d_m > width + kParkedMarginM;
      b.lane = std::clamp(core::lane_of(b.map_frenet.d_m, road), 0, road.lane_count - 1);
    }
    steps.push_back(std::move(cars));
  }
  return steps;
}

/// Watches a run driven on from a checkpoint: checks the ego against the recorded frames
/// and, once recording, keeps the cars' bodies at every step as traffic moved them (before
/// contacts pushed them apart: replayed, they then touch the ego when they did).
class Redrive final : public sim::RunObserver {
 public:
  Redrive(const sim::World& world, const replay::Replay& r) : world_(world), replay_(r) {}
  void on_frame(const sim::Frame& frame, std::span<const sim::Incident> /*new*/) override {
    const replay::ReplayFrame* rec = recorded(frame.step);
    if (rec && !diverged_ && core::distance(rec->position, frame.position) > kSameRunToleranceM) {
      diverged_ = "at t " + fixed_text(world_.time_s(), 2) + " s the ego is " +
                  fixed_text(core::distance(rec->position, frame.position), 3) +
                  " m from its recorded place";
    }
    if (recording_) bodies_.push_back(world_.moved_cars());
  }
  void on_path(std::span<const core::Vec2> /*path*/) override {}
  void start_recording() {
    bodies_.push_back(world_.traffic().cars());
    recording_ = true;
  }
  [[nodiscard]] const std::optional<std::string>& diverged() const { return diverged_; }
  [[nodiscard]] sim::RecordedTraffic take() { return std::move(bodies_); }

 private:
  const replay::ReplayFrame* recorded(long step) const {
    const auto& f = replay_.frames;
    if (f.empty()) return nullptr;
    const long k = step - f.front().step;
    if (k >= 0 && k < static_cast<long>(f.size()) && f[static_cast<std::size_t>(k)].step == step) {
      return &f[static_cast<std::size_t>(k)];
    }
    return nullptr;
  }
  const sim::World& world_;
  const replay::Replay& replay_;
  bool recording_ = false;
  sim::RecordedTraffic bodies_;
  std::optional<std::string> diverged_;
};

/// The report's fixed steps per call, if the run had them.
std::optional<int> fixed_steps_per_call(const replay::Replay& r) {
  try {
    const nlohmann::json j = nlohmann::json::parse(r.end_json);
    const nlohmann::json& v = j.at("config").at("steps_per_call");
    if (v.is_string()) {
      const std::string s = v.get<std::string>();
      if (!s.empty() &&
          std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; })) {
        return std::stoi(s);
      }
    }
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

/// How the run's planner is brought on a command line, from its report's provenance.
PlannerCall run_planner(const replay::Replay& r, const std::string& policy) {
  try {
    const nlohmann::json j = nlohmann::json::parse(r.end_json);
    return call_from_description(policy, j.at("config").value("planner", nlohmann::json()));
  } catch (const std::exception&) {
    return call_from_description(policy, nlohmann::json());
  }
}

std::string map_reference(const std::optional<std::filesystem::path>& map,
                          const std::filesystem::path& out) {
  if (!map) return {};
  std::error_code ec;
  const auto base = std::filesystem::absolute(out, ec).parent_path();
  const auto rel = std::filesystem::relative(std::filesystem::absolute(*map, ec), base, ec);
  return ec || rel.empty() ? std::filesystem::absolute(*map, ec).string() : rel.generic_string();
}

}  // namespace

std::string expect_json(const sim::ScenarioExpect& e) {
  ordered_json j = ordered_json::object();
  if (e.max_at_fault_collisions) j["at_fault_collisions"] = *e.max_at_fault_collisions;
  if (e.max_collisions) j["collisions"] = *e.max_collisions;
  if (e.max_incidents) j["incidents"] = *e.max_incidents;
  if (e.reach_lane) j["reach_lane"] = {{"lane", *e.reach_lane}, {"by_s", e.reach_lane_by_s}};
  if (e.min_distance_m) j["min_distance_m"] = *e.min_distance_m;
  return json_text(j);
}

namespace {

// The moments a cut is made of, in run time, checked against the run.
struct CutWindow {
  double first_t = 0.0;  ///< the run's first and last frames
  double last_t = 0.0;
  double end_t = 0.0;  ///< where the scenario ends
  long end_step = 0;
  double warm_start_t = 0.0;  ///< where a warm-up would start
};

CutWindow cut_window(const replay::Replay& r, const CutOptions& opts, const std::string& name,
                     CutResult& result) {
  if (r.frames.empty()) throw ConfigError(name + ": the replay has no frames");
  if (r.checkpoints.empty()) {
    throw ConfigError(name +
                      ": the replay carries no checkpoints (recorded before replays carried "
                      "them, with --checkpoint-every 0, or of a scripted or replayed scenario); "
                      "record the run again with --record");
  }
  const double step_s = r.header.step_s;
  CutWindow w;
  w.first_t = static_cast<double>(r.frames.front().step) * step_s;
  w.last_t = static_cast<double>(r.frames.back().step) * step_s;
  if (opts.at_s < w.first_t - kEps || opts.at_s > w.last_t + kEps) {
    throw UsageError("--at " + fixed_text(opts.at_s, 2) + " s is outside the run (" +
                     fixed_text(w.first_t, 2) + " to " + fixed_text(w.last_t, 2) + " s)");
  }
  result.asked_start_s = std::max(w.first_t, opts.at_s - opts.before_s - opts.lead_in_s);
  w.end_t = std::min(w.last_t, opts.at_s + opts.after_s);
  w.end_step = std::lround(w.end_t / step_s);
  // The judged part starts after the lead-in (which ends at the moment at the latest), and
  // the run's start and end may clip the window.
  const double judged_from_t = std::min(opts.at_s, result.asked_start_s + opts.lead_in_s);
  if (w.end_t - judged_from_t < kMinCutJudgedS - kEps) {
    throw UsageError("the scenario would judge " + fixed_text(w.end_t - judged_from_t, 2) +
                     " s (t " + fixed_text(judged_from_t, 2) + " to " + fixed_text(w.end_t, 2) +
                     " s, after the lead-in and within the run's " + fixed_text(w.first_t, 2) +
                     " to " + fixed_text(w.last_t, 2) + " s); it must judge at least " +
                     fixed_text(kMinCutJudgedS, 0) +
                     " s: give a larger --before or --after, or a " + "shorter --lead-in");
  }
  w.warm_start_t =
      opts.warm_up_all ? w.first_t : std::max(w.first_t, result.asked_start_s - opts.warm_up_s);
  return w;
}

using AnswerMap = std::unordered_map<long, const std::vector<core::Vec2>*>;

// What the run's planner answered, bit for bit, by the step it was told at (a run of a planner
// from outside recorded in lock-step carries them); empty when any path lacks its exact form.
AnswerMap recorded_answers(const replay::Replay& r) {
  AnswerMap answers;
  if (r.paths.empty()) return answers;
  for (const replay::ReplayPath& p : r.paths) {
    if (!p.has_exact) return {};
    answers[p.step] = &p.exact;
  }
  return answers;
}

// The last checkpoint at or before `t`.
sim::Checkpoint checkpoint_before(const replay::Replay& r, const std::string& name, double t) {
  const replay::ReplayCheckpoint* from = nullptr;
  for (const replay::ReplayCheckpoint& c : r.checkpoints) {
    if (c.t_s <= t + kEps) from = &c;
  }
  if (!from) {
    throw ConfigError(name + ": no checkpoint at or before t " + fixed_text(t, 2) +
                      " s (the first is at " + fixed_text(r.checkpoints.front().t_s, 2) + " s)");
  }
  try {
    return sim::decode_checkpoint(from->bytes,
                                  name + ": checkpoint at t " + fixed_text(from->t_s, 2));
  } catch (const core::StateError& e) {
    throw ConfigError(e.what());
  }
}

// The run's map: --map, else the one the checkpoint names; its hash must be the run's.
std::shared_ptr<const run::Track> run_track(const CutOptions& opts, const sim::Checkpoint& cp,
                                            const std::string& name,
                                            std::optional<std::filesystem::path>& map_path) {
  map_path = opts.map;
  if (!map_path && cp.info.track != kBuiltinMapSource) map_path = cp.info.track;
  if (map_path && !std::filesystem::exists(*map_path)) {
    throw ConfigError(name + ": the run was on the map " + map_path->string() +
                      ", which is not there; give --map FILE");
  }
  auto track = load_track(map_path);
  if (core::hex64(track->map.content_hash) != cp.info.map_hash) {
    throw ConfigError(name + ": the run was on a map of hash " + cp.info.map_hash + ", " +
                      track->map.source + " has hash " + core::hex64(track->map.content_hash) +
                      "; give the run's map with --map");
  }
  return track;
}

// What a cut starts from: the checkpoint, or the run driven on from it to the exact start.
struct CutStart {
  sim::Checkpoint start;
  sim::RecordedTraffic recorded;  ///< replayed traffic (with --replayed)
  sim::WarmUp warm;
  std::optional<std::string> diverged;  ///< why driving on did not repeat the run
};

// Drives the run on from `cp` with its own policy (or its recorded answers) to the exact
// start, keeping the warm-up's cycles from `warm_start_t` (when `keep_warm_up`) and, with
// --replayed, the traffic to the end.
CutStart drive_to_start(const replay::Replay& r, const CutOptions& opts, const run::Track& track,
                        const Config& config, const sim::Checkpoint& cp, planner::Policy* policy,
                        const AnswerMap& answers, const CutWindow& w, double start_t,
                        bool keep_warm_up) {
  const std::string name = opts.replay.string();
  CutStart out{cp, {}, {}, std::nullopt};
  out.warm.in_step_cycles = opts.in_step_cycles;
  out.warm.from_run_start = opts.warm_up_all;
  sim::World world(track.map, track.line, config.world,
                   *sim::parse_traffic_profile(cp.info.traffic), cp.info.seed);
  world.keep_moved_cars(true);
  Redrive watch(world, r);
  sim::RunOptions ro;
  ro.restore = cp.run;
  ro.observer = &watch;
  ro.steps_per_call = fixed_steps_per_call(r);
  const auto plan = [&](const core::Telemetry& t) {
    if (policy) return policy->plan(t);
    const auto it = answers.find(world.steps());
    if (it == answers.end()) {
      throw ConfigError(name + ": the replay holds no answer of the planner at t " +
                        fixed_text(world.time_s(), 2) + " s");
    }
    return core::normal_plan(*it->second);
  };
  bool warming = keep_warm_up;
  try {
    if (policy) (void)planner::restore_policy_state(*policy, cp.planner);
    sim::Stepper run(world, ro);
    const auto cycle = [&] {
      core::Telemetry told = run.telemetry();
      core::PlanResult answer = plan(told);
      if (warming && world.time_s() + kEps >= w.warm_start_t) {
        out.warm.cycles.push_back({world.steps(), std::move(told), answer.path});
      }
      run.apply(std::move(answer), 0.0);
      run.step_one_call();
    };
    while (!run.finished() && world.time_s() + kEps < start_t) cycle();
    warming = false;
    out.start.info.step = world.steps();
    out.start.info.t_s = world.time_s();
    out.start.run = run.save();
    out.start.planner = policy ? planner::save_policy_state(*policy) : std::string();
    if (opts.replayed) {
      watch.start_recording();
      while (!run.finished() && world.steps() < w.end_step) cycle();
      out.recorded = watch.take();
    }
  } catch (const core::StateError& e) {
    throw ConfigError(e.what());
  }
  out.diverged = watch.diverged();
  return out;
}

// What the scenario says of the planner's state at its start.
std::string planner_state_text(const CutResult& result, const sim::Checkpoint& start,
                               const sim::Checkpoint& cp, const sim::WarmUp& warm,
                               const std::string& why_not_exact, bool builtin) {
  std::string text;
  if (!start.planner.empty()) {
    text = "restored";
  } else if (result.has_warm_up) {
    text = "brought in step by the warm-up: the " + std::to_string(warm.cycles.size()) +
           " cycles it was told from t " + fixed_text(result.warm_up_start_s, 2) +
           " s are played to it before the start";
  } else {
    text = "the planner starts afresh: its state is not in the checkpoint (" + cp.info.policy +
           " keeps state overtake cannot see)";
    if (why_not_exact.empty() && !builtin) text += "; no warm-up (--warm-up 0)";
  }
  if (!why_not_exact.empty()) text += "; " + why_not_exact;
  return text;
}

// Refuses a blob beyond what a scenario may carry (`drive` would refuse it).
void check_blob_size(const std::string& bytes, const char* what, const CutResult& result) {
  if (bytes.size() <= kMaxBlobBytes) return;
  const double mib = static_cast<double>(bytes.size()) / static_cast<double>(1U << 20U);
  const double window_s = result.end_s - result.start_s;
  throw UsageError(
      std::string("the scenario's ") + what + " for t " + fixed_text(result.start_s, 2) + " to " +
      fixed_text(result.end_s, 2) + " s is " + fixed_text(mib, 1) + " MB, more than the " +
      std::to_string(kMaxBlobBytes >> 20U) + " MB a scenario may carry; cut " +
      "a window of at most about " +
      fixed_text(window_s * static_cast<double>(kMaxBlobBytes) / static_cast<double>(bytes.size()),
                 0) +
      " s (--before, --after and --lead-in together)");
}

// The scenario's name, description, duration and expectations.
ordered_json scenario_head(const CutOptions& opts, const CutResult& result,
                           const sim::Checkpoint& cp, double lead_in_s) {
  const std::string policy_name = cp.info.policy.empty() ? "the planner" : cp.info.policy;
  ordered_json j;
  j["name"] = opts.name.empty()
                  ? policy_name + ", " + cp.info.traffic + " traffic, seed " +
                        std::to_string(cp.info.seed) + ", t " + fixed_text(opts.at_s, 1) + " s"
                  : opts.name;
  j["description"] = !opts.description.empty()
                         ? opts.description
                         : "Cut from a run of " + policy_name + " (" + cp.info.traffic +
                               " traffic, seed " + std::to_string(cp.info.seed) + ", map " +
                               cp.info.track + ") around t " + fixed_text(opts.at_s, 2) + " s" +
                               (result.incident.empty() ? std::string() : ": " + result.incident) +
                               ".";
  const double duration_s = std::round((result.end_s - result.start_s) * 1e6) / 1e6;
  if (!(duration_s > lead_in_s)) {  // what `drive` would refuse (checked above; kept as a guard)
    throw UsageError("the scenario from t " + fixed_text(result.start_s, 2) + " to " +
                     fixed_text(result.end_s, 2) + " s with a lead-in of " +
                     fixed_text(lead_in_s, 2) + " s would judge nothing");
  }
  j["duration_s"] = duration_s;
  sim::ScenarioExpect no_fault;
  no_fault.max_at_fault_collisions = 0;
  j["expect"] = ordered_json::parse(expect_json(opts.expect.value_or(no_fault)));
  return j;
}

// The scenario's `cut` object: where it was cut from, and its blobs.
ordered_json cut_object(const CutOptions& opts, CutResult& result, const CutStart& from,
                        const sim::Checkpoint& cp, double lead_in_s,
                        const std::optional<std::filesystem::path>& map_path) {
  ordered_json cut;
  cut["traffic"] = opts.replayed ? "replayed" : "reactive";
  cut["start_s"] = result.start_s;
  cut["at_s"] = opts.at_s;
  cut["lead_in_s"] = lead_in_s;
  const std::string map_ref = map_reference(map_path, opts.out);
  if (!map_ref.empty()) cut["map"] = map_ref;
  cut["from"] = {{"replay", opts.replay.string()},
                 {"policy", cp.info.policy},
                 {"traffic", cp.info.traffic},
                 {"seed", cp.info.seed},
                 {"track", cp.info.track},
                 {"map_hash", cp.info.map_hash},
                 {"config_hash", cp.info.config_hash},
                 {"incident", result.incident},
                 {"exact_start", result.exact_start}};
  const std::string checkpoint = sim::encode_checkpoint(from.start);
  result.checkpoint_bytes = checkpoint.size();
  check_blob_size(checkpoint, "checkpoint", result);
  cut["checkpoint"] = pack_blob(checkpoint);
  if (opts.replayed) {
    const std::string traffic = sim::encode_recorded_traffic(from.recorded);
    check_blob_size(traffic, "replayed traffic", result);
    cut["recorded_traffic"] = pack_blob(traffic);
  }
  if (result.has_warm_up) {
    const std::string told = sim::encode_warm_up(from.warm);
    if (told.size() > kMaxWarmUpBytes) {
      throw UsageError("the warm-up from t " + fixed_text(result.warm_up_start_s, 2) + " s is " +
                       std::to_string(told.size() >> 20U) + " MB, more than the " +
                       std::to_string(kMaxWarmUpBytes >> 20U) +
                       " MB a scenario may carry; give a shorter --warm-up");
    }
    cut["warm_up"] = {{"start_s", result.warm_up_start_s},
                      {"cycles", from.warm.cycles.size()},
                      {"in_step_cycles", from.warm.in_step_cycles},
                      {"from_run_start", from.warm.from_run_start},
                      {"telemetry", pack_blob(told)}};
  }
  return cut;
}

}  // namespace

CutResult cut_replay(const CutOptions& opts) {
  check_options(opts);
  const replay::Replay r = replay::read_replay(opts.replay);
  const std::string name = opts.replay.string();
  CutResult result;
  const CutWindow w = cut_window(r, opts, name, result);
  result.incident = incident_near(r, opts.at_s);
  const AnswerMap answers = recorded_answers(r);
  sim::Checkpoint cp = checkpoint_before(r, name, result.asked_start_s);
  if (!sim::parse_traffic_profile(cp.info.traffic))
    throw ConfigError(name + ": a run of " + cp.info.traffic + " traffic cannot be cut");
  std::optional<std::filesystem::path> map_path;
  const auto track = run_track(opts, cp, name, map_path);
  const Config config = load_config(opts.config);
  auto policy = planner::make_policy(cp.info.policy, track->line, config.planner);
  std::string why_not_exact;
  if (!policy && answers.empty()) {
    why_not_exact = "the run's planner (" + cp.info.policy +
                    ") is not a built-in policy and the replay does not carry its exact answers "
                    "(recorded before replays kept them, or in real time), so the run cannot be "
                    "driven on from the checkpoint";
  } else if (config_hash(config) != cp.info.config_hash) {
    why_not_exact = "the parameters differ from the run's (config hash " + config_hash(config) +
                    ", the run's " + cp.info.config_hash + ")";
  }
  // A planner from outside, driven on with its recorded answers: from the checkpoint before the
  // warm-up, whose cycles are kept.
  const bool keep_warm_up =
      why_not_exact.empty() && !policy && (opts.warm_up_all || opts.warm_up_s > 0.0);
  if (keep_warm_up && w.warm_start_t + kEps < cp.info.t_s)
    cp = checkpoint_before(r, name, w.warm_start_t);
  CutStart from{cp, {}, {}, std::nullopt};
  if (why_not_exact.empty()) {
    from = drive_to_start(r, opts, *track, config, cp, policy.get(), answers, w,
                          result.asked_start_s, keep_warm_up);
    if (from.diverged) {
      why_not_exact = "driven on from the checkpoint, the run does not replay the same (" +
                      *from.diverged + "): it was recorded by another build";
      cp = checkpoint_before(r, name, result.asked_start_s);
      from = CutStart{cp, {}, {}, std::nullopt};
    } else {
      result.exact_start = true;
      result.has_warm_up = keep_warm_up;
    }
  }
  if (!result.exact_start && opts.replayed)
    from.recorded = bodies_from_frames(r, cp.info.step, w.end_step, track->map, config.road);
  if (result.has_warm_up) {
    result.warm_up_cycles = from.warm.cycles.size();
    result.warm_up_start_s =
        from.warm.cycles.empty()
            ? from.start.info.t_s
            : static_cast<double>(from.warm.cycles.front().step) * r.header.step_s;
  }
  result.planner_state =
      planner_state_text(result, from.start, cp, from.warm, why_not_exact, policy != nullptr);
  result.start_s = from.start.info.t_s;
  result.policy = cp.info.policy;
  result.drive_command = planner_command_line(run_planner(r, cp.info.policy)) + " --scenario " +
                         shell_quote(opts.out.string());
  result.end_s = std::max(result.start_s, w.end_t);
  const double lead_in_s = std::max(0.0, std::min(opts.lead_in_s, opts.at_s - result.start_s));
  ordered_json j = scenario_head(opts, result, cp, lead_in_s);
  j["cut"] = cut_object(opts, result, from, cp, lead_in_s, map_path);
  const std::string text = json_text(j, 2) + "\n";
  result.file_bytes = text.size();
  write_file_atomic(opts.out, text);
  return result;
}

}  // namespace overtake::scenarios
