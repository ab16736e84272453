#include "overtake/app/cut.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <sstream>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "overtake/app/cli.hpp"
#include "overtake/app/commands.hpp"
#include "overtake/app/config.hpp"
#include "overtake/app/io.hpp"
#include "overtake/app/planners.hpp"
#include "overtake/app/report.hpp"
#include "overtake/app/scenario_file.hpp"
#include "overtake/core/hash.hpp"
#include "overtake/core/units.hpp"
#include "overtake/core/waypoint_frenet.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/replay/replay.hpp"
#include "overtake/sim/checkpoint.hpp"
#include "overtake/sim/recorded_traffic.hpp"
#include "overtake/sim/world.hpp"

namespace overtake::app {
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

constexpr const char* kBuiltinMapSource = "builtin:default";
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
    text += std::string(" ") + std::string(sim::to_string(best->collision->kind)) +
            (best->collision->at_fault ? " (at fault)" : " (not at fault)");
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

CutResult cut_replay(const CutOptions& opts) {
  check_options(opts);
  const replay::Replay r = replay::read_replay(opts.replay);
  const std::string name = opts.replay.string();
  if (r.frames.empty()) throw ConfigError(name + ": the replay has no frames");
  if (r.checkpoints.empty()) {
    throw ConfigError(name +
                      ": the replay carries no checkpoints (recorded before replays carried "
                      "them, with --checkpoint-every 0, or of a scripted or replayed scenario); "
                      "record the run again with --record");
  }
  const double step_s = r.header.step_s;
  const double first_t = static_cast<double>(r.frames.front().step) * step_s;
  const double last_t = static_cast<double>(r.frames.back().step) * step_s;
  if (opts.at_s < first_t - kEps || opts.at_s > last_t + kEps) {
    throw UsageError("--at " + fixed_text(opts.at_s, 2) + " s is outside the run (" +
                     fixed_text(first_t, 2) + " to " + fixed_text(last_t, 2) + " s)");
  }
  CutResult result;
  result.asked_start_s = std::max(first_t, opts.at_s - opts.before_s - opts.lead_in_s);
  const double end_t = std::min(last_t, opts.at_s + opts.after_s);
  const long end_step = std::lround(end_t / step_s);
  // The judged part starts after the lead-in (which ends at the moment at the latest), and
  // the run's start and end may clip the window.
  const double judged_from_t = std::min(opts.at_s, result.asked_start_s + opts.lead_in_s);
  if (end_t - judged_from_t < kMinCutJudgedS - kEps) {
    throw UsageError("the scenario would judge " + fixed_text(end_t - judged_from_t, 2) + " s (t " +
                     fixed_text(judged_from_t, 2) + " to " + fixed_text(end_t, 2) +
                     " s, after the lead-in and within the run's " + fixed_text(first_t, 2) +
                     " to " + fixed_text(last_t, 2) + " s); it must judge at least " +
                     fixed_text(kMinCutJudgedS, 0) +
                     " s: give a larger --before or --after, or a " + "shorter --lead-in");
  }
  result.incident = incident_near(r, opts.at_s);

  // What the run's planner answered, bit for bit, by the step it was told at (a run of a
  // planner from outside recorded in lock-step carries them).
  std::unordered_map<long, const std::vector<core::Vec2>*> answers;
  bool exact_answers = !r.paths.empty();
  for (const replay::ReplayPath& p : r.paths) {
    if (!p.has_exact) {
      exact_answers = false;
      break;
    }
    answers[p.step] = &p.exact;
  }
  if (!exact_answers) answers.clear();
  const bool warm_up = opts.warm_up_all || opts.warm_up_s > 0.0;
  const double warm_start_t =
      opts.warm_up_all ? first_t : std::max(first_t, result.asked_start_s - opts.warm_up_s);

  // The last checkpoint at or before the start (or the warm-up's start).
  const auto checkpoint_before = [&](double t) {
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
  };
  sim::Checkpoint cp = checkpoint_before(result.asked_start_s);
  const auto profile = sim::parse_traffic_profile(cp.info.traffic);
  if (!profile)
    throw ConfigError(name + ": a run of " + cp.info.traffic + " traffic cannot be cut");

  std::optional<std::filesystem::path> map_path = opts.map;
  if (!map_path && cp.info.track != kBuiltinMapSource) map_path = cp.info.track;
  if (map_path && !std::filesystem::exists(*map_path)) {
    throw ConfigError(name + ": the run was on the map " + map_path->string() +
                      ", which is not there; give --map FILE");
  }
  const auto track = load_track(map_path);
  if (core::hex64(track->map.content_hash) != cp.info.map_hash) {
    throw ConfigError(name + ": the run was on a map of hash " + cp.info.map_hash + ", " +
                      track->map.source + " has hash " + core::hex64(track->map.content_hash) +
                      "; give the run's map with --map");
  }
  const Config config = load_config(opts.config);
  const bool same_config = config_hash(config) == cp.info.config_hash;

  auto policy = planner::make_policy(cp.info.policy, track->line, config.planner);
  std::string why_not_exact;
  if (!policy && !exact_answers) {
    why_not_exact = "the run's planner (" + cp.info.policy +
                    ") is not a built-in policy and the replay does not carry its exact answers "
                    "(recorded before replays kept them, or in real time), so the run cannot be "
                    "driven on from the checkpoint";
  } else if (!same_config) {
    why_not_exact = "the parameters differ from the run's (config hash " + config_hash(config) +
                    ", the run's " + cp.info.config_hash + ")";
  }
  // A planner from outside, driven on with its recorded answers: from the checkpoint before the
  // warm-up, whose cycles are kept.
  const bool keep_warm_up = why_not_exact.empty() && !policy && warm_up;
  if (keep_warm_up && warm_start_t + kEps < cp.info.t_s) cp = checkpoint_before(warm_start_t);

  sim::Checkpoint start = cp;
  sim::RecordedTraffic recorded;
  sim::WarmUp warm;
  warm.in_step_cycles = opts.in_step_cycles;
  warm.from_run_start = opts.warm_up_all;
  if (why_not_exact.empty()) {
    // Drive the run on from the checkpoint with its own policy (or its recorded answers), to
    // the exact start.
    sim::World world(track->map, track->line, config.world, *profile, cp.info.seed);
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
        if (warming && world.time_s() + kEps >= warm_start_t) {
          warm.cycles.push_back({world.steps(), std::move(told), answer.path});
        }
        run.apply(std::move(answer), 0.0);
        run.step_one_call();
      };
      while (!run.finished() && world.time_s() + kEps < result.asked_start_s) cycle();
      warming = false;
      start.info.step = world.steps();
      start.info.t_s = world.time_s();
      start.run = run.save();
      start.planner = policy ? planner::save_policy_state(*policy) : std::string();
      if (opts.replayed) {
        watch.start_recording();
        while (!run.finished() && world.steps() < end_step) cycle();
        recorded = watch.take();
      }
    } catch (const core::StateError& e) {
      throw ConfigError(e.what());
    }
    if (watch.diverged()) {
      why_not_exact = "driven on from the checkpoint, the run does not replay the same (" +
                      *watch.diverged() + "): it was recorded by another build";
      cp = checkpoint_before(result.asked_start_s);
      start = cp;
      recorded.clear();
      warm.cycles.clear();
    } else {
      result.exact_start = true;
      result.has_warm_up = keep_warm_up;
    }
  }
  if (!result.exact_start && opts.replayed) {
    recorded = bodies_from_frames(r, cp.info.step, end_step, track->map, config.road);
  }
  if (!start.planner.empty()) {
    result.planner_state = "restored";
  } else if (result.has_warm_up) {
    result.warm_up_cycles = warm.cycles.size();
    result.warm_up_start_s = warm.cycles.empty()
                                 ? start.info.t_s
                                 : static_cast<double>(warm.cycles.front().step) * r.header.step_s;
    result.planner_state = "brought in step by the warm-up: the " +
                           std::to_string(warm.cycles.size()) + " cycles it was told from t " +
                           fixed_text(result.warm_up_start_s, 2) +
                           " s are played to it before the start";
  } else {
    result.planner_state = "the planner starts afresh: its state is not in the checkpoint (" +
                           cp.info.policy + " keeps state overtake cannot see)";
    if (why_not_exact.empty() && !policy) result.planner_state += "; no warm-up (--warm-up 0)";
  }
  if (!why_not_exact.empty()) result.planner_state += "; " + why_not_exact;
  result.start_s = start.info.t_s;
  result.policy = cp.info.policy;
  result.drive_command = planner_command_line(run_planner(r, cp.info.policy)) + " --scenario " +
                         shell_quote(opts.out.string());
  result.end_s = std::max(result.start_s, end_t);

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
  const double lead_in_s = std::max(0.0, std::min(opts.lead_in_s, opts.at_s - result.start_s));
  if (!(duration_s > lead_in_s)) {  // what `drive` would refuse (checked above; kept as a guard)
    throw UsageError("the scenario from t " + fixed_text(result.start_s, 2) + " to " +
                     fixed_text(result.end_s, 2) + " s with a lead-in of " +
                     fixed_text(lead_in_s, 2) + " s would judge nothing");
  }
  j["duration_s"] = duration_s;
  sim::ScenarioExpect no_fault;
  no_fault.max_at_fault_collisions = 0;
  j["expect"] = ordered_json::parse(expect_json(opts.expect.value_or(no_fault)));
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
  const std::string checkpoint = sim::encode_checkpoint(start);
  result.checkpoint_bytes = checkpoint.size();
  // A blob beyond what a scenario may carry would be refused by `drive`: refused here first.
  const auto check_size = [&](const std::string& bytes, const char* what) {
    if (bytes.size() <= kMaxBlobBytes) return;
    const double mib = static_cast<double>(bytes.size()) / static_cast<double>(1U << 20U);
    const double window_s = result.end_s - result.start_s;
    throw UsageError(
        std::string("the scenario's ") + what + " for t " + fixed_text(result.start_s, 2) + " to " +
        fixed_text(result.end_s, 2) + " s is " + fixed_text(mib, 1) + " MB, more than the " +
        std::to_string(kMaxBlobBytes >> 20U) + " MB a scenario may carry; cut " +
        "a window of at most about " +
        fixed_text(
            window_s * static_cast<double>(kMaxBlobBytes) / static_cast<double>(bytes.size()), 0) +
        " s (--before, --after and --lead-in together)");
  };
  check_size(checkpoint, "checkpoint");
  cut["checkpoint"] = pack_blob(checkpoint);
  if (opts.replayed) {
    const std::string traffic = sim::encode_recorded_traffic(recorded);
    check_size(traffic, "replayed traffic");
    cut["recorded_traffic"] = pack_blob(traffic);
  }
  if (result.has_warm_up) {
    const std::string told = sim::encode_warm_up(warm);
    if (told.size() > kMaxWarmUpBytes) {
      throw UsageError("the warm-up from t " + fixed_text(result.warm_up_start_s, 2) + " s is " +
                       std::to_string(told.size() >> 20U) + " MB, more than the " +
                       std::to_string(kMaxWarmUpBytes >> 20U) +
                       " MB a scenario may carry; give a shorter --warm-up");
    }
    cut["warm_up"] = {{"start_s", result.warm_up_start_s},
                      {"cycles", warm.cycles.size()},
                      {"in_step_cycles", warm.in_step_cycles},
                      {"from_run_start", warm.from_run_start},
                      {"telemetry", pack_blob(told)}};
  }
  j["cut"] = std::move(cut);
  const std::string text = json_text(j, 2) + "\n";
  result.file_bytes = text.size();
  write_file_atomic(opts.out, text);
  return result;
}

Subcommand register_cut(CLI::App& app) {
  struct State {
    CutOptions o;
    std::string traffic = "reactive";
    std::string expect;
    std::string config, map;
    std::string warm_up = fixed_text(kDefaultWarmUpS, 0);
    bool quiet = false;
  };
  auto st = std::make_shared<State>();
  auto* cmd = app.add_subcommand(
      "cut",
      "Cut a scenario from a recorded run: it starts --before seconds before the moment --at\n"
      "and lasts until --after seconds after it, from the world's exact state (replays carry\n"
      "checkpoints). Drive it with `overtake drive --scenario FILE`, or run a folder of them\n"
      "with `overtake bench --scenarios DIR` (docs/scenarios.md).");
  cmd->add_option("replay", st->o.replay, "A replay written by --record")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--at", st->o.at_s, "The moment that matters (run time, seconds)")->required();
  cmd->add_option("-o,--out", st->o.out, "The scenario file to write")->required();
  cmd->add_option("--before", st->o.before_s, "Seconds before the moment to start")
      ->capture_default_str();
  cmd->add_option("--after", st->o.after_s, "Seconds after the moment to end")
      ->capture_default_str();
  cmd->add_option("--lead-in", st->o.lead_in_s,
                  "Start this many seconds earlier still, for a planner that keeps its own\n"
                  "state (a target speed starting at 0) to settle; not judged")
      ->capture_default_str();
  cmd->add_option("--warm-up", st->warm_up,
                  "For a run of a planner from outside (a program, a plugin, Python): the\n"
                  "seconds before the start whose telemetry the scenario carries, played to the\n"
                  "planner before it drives so that it comes in step; `all`: from the run's first\n"
                  "cycle; 0: none")
      ->capture_default_str();
  cmd->add_option("--traffic", st->traffic,
                  "reactive: the cars start from their recorded state and keep driving by\n"
                  "their rules (they react to another planner); replayed: every car follows its\n"
                  "recorded trajectory whatever the ego does")
      ->capture_default_str();
  cmd->add_option("--expect", st->expect,
                  "What the scenario expects, as JSON (default {\"at_fault_collisions\": 0}):\n"
                  "at_fault_collisions, collisions, incidents (at most so many), reach_lane\n"
                  "{\"lane\": L, \"by_s\": T}, min_distance_m");
  cmd->add_option("--name", st->o.name, "The scenario's name (default: the run and the moment)");
  cmd->add_option("--description", st->o.description, "What happens in it");
  cmd->add_option("--config", st->config, "The parameters the run used (default: the defaults)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--map", st->map, "The run's map, when it is no longer where the replay says")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--quiet,-q", st->quiet, "Print nothing");
  return {cmd, [st] {
            CutOptions o = st->o;
            if (st->traffic != "reactive" && st->traffic != "replayed") {
              throw UsageError("--traffic: '" + st->traffic + "' is neither reactive nor replayed");
            }
            o.replayed = st->traffic == "replayed";
            parse_warm_up(st->warm_up, o.warm_up_s, o.warm_up_all);
            if (!st->config.empty()) o.config = st->config;
            if (!st->map.empty()) o.map = st->map;
            if (!st->expect.empty()) {
              const nlohmann::json j = parse_json_text(st->expect, "--expect");
              o.expect = parse_scenario(nlohmann::json{{"expect", j}}, "--expect", {}).expect;
            }
            const CutResult res = cut_replay(o);
            if (!st->quiet) {
              std::cout << "wrote " << o.out.string() << " (" << res.file_bytes / 1024
                        << " KiB): t " << fixed_text(res.start_s, 2) << " to "
                        << fixed_text(res.end_s, 2) << " s, "
                        << (o.replayed ? "replayed" : "reactive") << " traffic\n";
              if (!res.exact_start) {
                std::cout << "  starts at the checkpoint at t " << fixed_text(res.start_s, 2)
                          << " s, " << fixed_text(res.asked_start_s - res.start_s, 2)
                          << " s before the asked start\n";
              }
              std::cout << "  planner: " << res.planner_state << "\n";
              if (!res.incident.empty()) std::cout << "  near the moment: " << res.incident << "\n";
              std::cout << "drive it: " << res.drive_command << "\n";
            }
            return 0;
          }};
}

}  // namespace overtake::app
