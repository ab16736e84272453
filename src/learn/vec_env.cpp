#include "overtake/learn/vec_env.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <thread>
#include <utility>

#include "overtake/core/cpu_clock.hpp"
#include "overtake/core/plan.hpp"
#include "overtake/learn/command.hpp"
#include "overtake/learn/observation.hpp"
#include "overtake/learn/step_pool.hpp"
#include "overtake/planner/reference/reference_policy.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "overtake/sim/faithful_traffic.hpp"
#include "overtake/sim/run.hpp"
#include "overtake/sim/world.hpp"

namespace overtake::learn {

using planner::reference::DrivingCommand;
using planner::reference::ReferencePolicy;

ActionKind parse_action_kind(std::string_view text) {
  if (text == "meta") return ActionKind::meta;
  if (text == "continuous") return ActionKind::continuous;
  if (text == "path") return ActionKind::path;
  throw std::invalid_argument("actions: '" + std::string(text) +
                              "' is not a kind of action (meta, continuous or path)");
}

std::string_view to_string(ActionKind kind) {
  switch (kind) {
    case ActionKind::meta:
      return "meta";
    case ActionKind::continuous:
      return "continuous";
    case ActionKind::path:
      return "path";
  }
  return "meta";
}

namespace {

/// Episode k of an env seeded `base` drives the world of seed base + k x 2^32: its first
/// episode is the drive of seed `base`, and no two envs of one VecEnv share a world.
constexpr std::uint64_t kEpisodeSeedStride = std::uint64_t{1} << 32;
constexpr double kMaxMinutes = 24.0 * 60.0;
constexpr std::size_t kMaxEnvs = 100000;

// One env: its world, the run on it, the executor of its decisions and what it remembers.
struct Slot {
  std::uint64_t base_seed = 0;
  std::unique_ptr<sim::World> world;
  std::unique_ptr<sim::Stepper> stepper;  // refers to world: reset before it
  std::unique_ptr<ReferencePolicy> executor;
  run::RunProvenance provenance;
  EgoContext ego;
  // The telemetry read at the end of the last step, which the next one starts from (the world
  // does not move between calls); none after a reset.
  std::optional<core::Telemetry> telemetry;
  double last_speed_mps = 0.0;
  double last_distance_m = 0.0;
  std::size_t incidents_seen = 0;
  bool pending_reset = false;
  EnvStatus status;
  nlohmann::json last_report;
};

}  // namespace

struct VecEnv::Impl {
  VecEnvSpec spec;
  EnvParams params;
  run::DriveInputs inputs;
  sim::TrafficProfile profile{};
  // Faithful traffic's table of the map, built once for every world of every episode.
  std::shared_ptr<const sim::OpenRoadTable> open_road;
  // The executor's smoothed line and lane frame, built once for every reference policy.
  std::shared_ptr<const planner::reference::ReferenceGeometry> geometry;
  std::vector<Slot> slots;
  std::unique_ptr<StepPool> pool;
  // The executors' sample buffers, one set per thread of the pool: the worlds a thread steps
  // in turn plan in the same memory, which stays in its core's cache.
  std::vector<planner::reference::TrajectoryScratch> scratch;
  std::size_t obs_size = 0;
  bool reset_done = false;

  [[nodiscard]] const run::Config& config() const { return inputs.config; }
  [[nodiscard]] double cruise_mps() const {
    return config().planner.reference.behaviour.cruise_speed_mps;
  }

  void begin_episode(Slot& s, std::uint64_t seed);
  void write_observation(Slot& s, const core::Telemetry& t, float* out) const;
  void check_actions(const Actions& a) const;
  [[nodiscard]] core::PlanResult decide(Slot& s, const Actions& a, std::size_t i,
                                        const core::Telemetry& t, std::size_t worker,
                                        int& asked_lane);
  void step_env(std::size_t i, std::size_t worker, const Actions& a, const StepOutputs& out);
  [[nodiscard]] float reward_of(Slot& s, bool& collided);
};

void VecEnv::Impl::begin_episode(Slot& s, std::uint64_t seed) {
  const run::Track& track = *inputs.track;
  s.stepper.reset();
  s.telemetry.reset();
  s.world =
      std::make_unique<sim::World>(track.map, track.line, config().world, profile, seed, open_road);
  sim::RunOptions run;
  run.duration_s = spec.minutes * 60.0;
  run.steps_per_call = params.decision_steps;
  run.seed = seed;
  s.stepper = std::make_unique<sim::Stepper>(*s.world, run);
  s.executor = std::make_unique<ReferencePolicy>(track.line, config().planner, geometry);
  run::DriveOptions o = inputs.options;
  o.seed = seed;
  s.provenance = run::drive_provenance(track, config(), o, nullptr);
  const core::Telemetry t = s.stepper->telemetry();
  const int lane =
      std::clamp(core::lane_of(t.ego.d_m, config().road), 0, config().road.lane_count - 1);
  s.ego = {lane, cruise_mps(), 0.0, 0.0};
  s.last_speed_mps = t.ego.speed_mps;
  s.last_distance_m = 0.0;
  s.incidents_seen = 0;
  s.pending_reset = false;
  const long episode = s.status.episode + 1;
  s.status = {};
  s.status.episode_seed = seed;
  s.status.episode = episode;
  s.status.was_reset = true;
  s.status.lane = lane;
  s.status.target_lane = lane;
  s.status.target_speed_mps = s.ego.target_speed_mps;
}

void VecEnv::Impl::write_observation(Slot& s, const core::Telemetry& t, float* out) const {
  observe(t, s.ego, config().road, inputs.track->map.loop_length_m, config().car.length_m,
          params.observation, std::span<float>(out, obs_size));
}

void VecEnv::Impl::check_actions(const Actions& a) const {
  const std::size_t n = slots.size();
  const auto bad = [](std::size_t env, const std::string& what) {
    throw std::invalid_argument("the action of env " + std::to_string(env) + " " + what);
  };
  switch (spec.actions) {
    case ActionKind::meta:
      if (a.meta == nullptr) throw std::invalid_argument("step: no meta-actions given");
      for (std::size_t i = 0; i < n; ++i) {
        if (a.meta[i] < 0 || a.meta[i] >= kMetaActions) {
          bad(i, "is " + std::to_string(a.meta[i]) +
                     ": a meta-action is 0 keep, 1 left, 2 right, 3 faster or 4 slower");
        }
      }
      break;
    case ActionKind::continuous:
      if (a.continuous == nullptr) throw std::invalid_argument("step: no continuous actions given");
      for (std::size_t i = 0; i < n; ++i) {
        const float speed = a.continuous[2 * i];
        const float lane = a.continuous[2 * i + 1];
        if (!(speed >= 0.0F && speed <= 1.0F))
          bad(i, "has target speed " + std::to_string(speed) + ": it must be in [0, 1]");
        if (!(lane >= -1.0F && lane <= 1.0F))
          bad(i, "has target lane " + std::to_string(lane) + ": it must be in [-1, 1]");
      }
      break;
    case ActionKind::path:
      if (a.path == nullptr) throw std::invalid_argument("step: no paths given");
      if (a.path_points > static_cast<std::size_t>(params.max_path_points)) {
        throw std::invalid_argument("step: paths of " + std::to_string(a.path_points) +
                                    " points; at most max_path_points (" +
                                    std::to_string(params.max_path_points) + ")");
      }
      for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t k = 0; k < a.path_points; ++k) {
          const double x = a.path[(i * a.path_points + k) * 2];
          const double y = a.path[(i * a.path_points + k) * 2 + 1];
          if (std::isnan(x) && std::isnan(y)) break;  // the path ends here
          if (!std::isfinite(x) || !std::isfinite(y)) {
            bad(i, "has point " + std::to_string(k) +
                       " not finite (a row of two NaN ends a path; one NaN is an error)");
          }
        }
      }
      break;
  }
}

// This decision's plan: the raw path, or the executor's plan of the agent's command.
// `asked_lane`: the lane the agent asked for (-1 for a path).
core::PlanResult VecEnv::Impl::decide(Slot& s, const Actions& a, std::size_t i,
                                      const core::Telemetry& t, std::size_t worker,
                                      int& asked_lane) {
  asked_lane = -1;
  if (spec.actions == ActionKind::path) {
    std::vector<core::Vec2> points;
    for (std::size_t k = 0; k < a.path_points; ++k) {
      const double x = a.path[(i * a.path_points + k) * 2];
      const double y = a.path[(i * a.path_points + k) * 2 + 1];
      if (std::isnan(x)) break;
      points.push_back({x, y});
    }
    core::PlanResult plan = core::normal_plan(std::move(points));
    plan.status_known = false;
    return plan;
  }
  const int lanes = config().road.lane_count;
  EgoContext& e = s.ego;
  if (spec.actions == ActionKind::meta) {
    apply_meta(e, a.meta[i], lanes, cruise_mps(), params.speed_step_mps);
  } else {
    apply_continuous(e, a.continuous[2 * i], a.continuous[2 * i + 1], lanes, cruise_mps());
  }
  asked_lane = e.target_lane;
  s.executor->set_command(DrivingCommand{e.target_lane, e.target_speed_mps});
  return s.executor->plan(t, scratch[worker]);
}

// The reward of the decision just stepped, from the distance driven and the new incidents.
float VecEnv::Impl::reward_of(Slot& s, bool& collided) {
  const RewardParams& w = params.reward;
  const sim::Referee& referee = s.stepper->scorecard().referee();
  const double decision_s = params.decision_steps * config().world.step_s;
  const double driven = referee.distance_m() - s.last_distance_m;
  s.last_distance_m = referee.distance_m();
  double r = w.progress * driven / (config().world.referee.speed_limit_mps * decision_s);
  const auto& all = referee.incidents();
  collided = false;
  for (std::size_t k = s.incidents_seen; k < all.size(); ++k) {
    const sim::Incident& inc = all[k];
    ++s.status.incidents;
    switch (inc.type) {
      case sim::IncidentType::collision:
        collided = true;
        ++s.status.collisions;
        r -= w.collision;
        if (inc.collision && inc.collision->at_fault) {
          ++s.status.at_fault;
          r -= w.at_fault;
        }
        break;
      case sim::IncidentType::speeding:
        r -= w.speeding;
        break;
      case sim::IncidentType::max_acceleration:
        r -= w.max_acceleration;
        break;
      case sim::IncidentType::max_jerk:
        r -= w.max_jerk;
        break;
      case sim::IncidentType::outside_lane:
        r -= w.outside_lane;
        break;
    }
  }
  s.incidents_seen = all.size();
  return static_cast<float>(r);
}

void VecEnv::Impl::step_env(std::size_t i, std::size_t worker, const Actions& a,
                            const StepOutputs& out) {
  Slot& s = slots[i];
  float* obs = out.observation + i * obs_size;
  if (s.pending_reset) {  // next-step autoreset: this call begins the next episode
    begin_episode(s, s.status.episode_seed + kEpisodeSeedStride);
    write_observation(s, s.stepper->telemetry(), obs);
    out.reward[i] = 0.0F;
    out.terminated[i] = 0;
    out.truncated[i] = 0;
    return;
  }
  s.status.was_reset = false;
  const core::Telemetry t =
      s.telemetry ? *std::exchange(s.telemetry, std::nullopt) : s.stepper->telemetry();
  const int lane_before = s.status.target_lane;
  int asked_lane = -1;
  bool failed = false;
  const double c0 = core::thread_cpu_us();
  const auto w0 = std::chrono::steady_clock::now();
  try {
    core::PlanResult plan = decide(s, a, i, t, worker, asked_lane);
    const double cycle_us = core::thread_cpu_us() - c0;
    const double wall_us =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - w0).count();
    s.stepper->apply(std::move(plan), cycle_us, wall_us);
    s.stepper->step_one_call();
  } catch (const std::exception& e) {
    s.stepper->end(sim::RunEnd::planner_failed, std::string("the executor failed: ") + e.what());
    failed = true;
  }
  if (asked_lane >= 0) {
    // A lane change the trajectory layer did not take is dropped, as the reference's
    // behaviour drops it.
    const int end_lane = s.executor->last_plan().trajectory.end_lane;
    if (end_lane != s.ego.target_lane) s.ego.target_lane = end_lane;
  }
  bool collided = false;
  float reward = reward_of(s, collided);
  core::Telemetry now = s.stepper->telemetry();
  const double decision_s = params.decision_steps * config().world.step_s;
  s.ego.accel_mps2 = (now.ego.speed_mps - s.last_speed_mps) / decision_s;
  s.last_speed_mps = now.ego.speed_mps;
  // The time since the target lane last changed, a decision's time after a change.
  if (s.ego.target_lane != lane_before) {
    s.ego.manoeuvre_s = decision_s;
    reward -= static_cast<float>(params.reward.lane_change);
  } else {
    s.ego.manoeuvre_s += decision_s;
  }
  const bool planner_failed = failed || (s.stepper->finished() && s.stepper->report().outcome.end ==
                                                                      sim::RunEnd::planner_failed);
  bool terminated = planner_failed;
  if (!terminated && collided && params.terminate_on_collision) {
    terminated = true;
    if (!s.stepper->finished()) {
      s.stepper->end(sim::RunEnd::stopped,
                     "the episode ended at a collision (terminate_on_collision)");
    }
  }
  const bool truncated = !terminated && s.stepper->finished();
  write_observation(s, now, obs);
  out.reward[i] = reward;
  out.terminated[i] = terminated ? 1 : 0;
  out.truncated[i] = truncated ? 1 : 0;
  EnvStatus& st = s.status;
  st.time_s = s.world->time_s();
  st.distance_m = s.last_distance_m;
  st.speed_mps = now.ego.speed_mps;
  st.lane = std::clamp(core::lane_of(now.ego.d_m, config().road), 0, config().road.lane_count - 1);
  st.target_lane = s.ego.target_lane;
  st.target_speed_mps = s.ego.target_speed_mps;
  st.episode_return += reward;
  st.episode_length += 1;
  if (terminated || truncated) {
    s.last_report = run::report_to_json(s.stepper->report(), s.provenance);
    s.pending_reset = true;
  } else {
    s.telemetry = std::move(now);
  }
}

VecEnv::VecEnv(const VecEnvSpec& spec) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.spec = spec;
  if (spec.num_envs < 1 || spec.num_envs > kMaxEnvs) {
    throw std::invalid_argument("num_envs must be from 1 to " + std::to_string(kMaxEnvs) +
                                " (got " + std::to_string(spec.num_envs) + ")");
  }
  if (!(spec.minutes > 0.0) || spec.minutes > kMaxMinutes) {
    throw std::invalid_argument("minutes must be more than 0 and at most " +
                                std::to_string(static_cast<int>(kMaxMinutes)));
  }
  if (spec.threads < 0 || spec.threads > 1024) {
    throw std::invalid_argument("threads must be from 0 (one per core) to 1024");
  }
  const auto profile = sim::parse_traffic_profile(spec.traffic);
  if (!profile) {
    throw std::invalid_argument("traffic: '" + spec.traffic +
                                "' is not a traffic profile (faithful or calm)");
  }
  m.profile = *profile;
  m.params = load_env_params(spec.params);
  run::DriveOptions o;
  o.map = spec.map;
  o.config = spec.config;
  o.traffic = spec.traffic;
  o.minutes = spec.minutes;
  o.policy = spec.name;
  o.steps_per_call = m.params.decision_steps;
  m.inputs = run::load_drive_inputs(o);
  const int lanes = m.config().road.lane_count;
  if (lanes < 1 || lanes > static_cast<int>(kMaxLanes)) {
    throw std::invalid_argument("the road has " + std::to_string(lanes) + " lanes; at most " +
                                std::to_string(kMaxLanes) + " are observed");
  }
  m.obs_size = learn::observation_size(lanes);
  if (m.profile == sim::TrafficProfile::faithful) {
    const sim::WorldParams& w = m.config().world;
    m.open_road = sim::build_open_road_table(m.inputs.track->line, w.road, w.traffic.faithful);
  }
  m.geometry =
      planner::reference::make_reference_geometry(m.inputs.track->line, m.config().planner);
  m.slots.resize(spec.num_envs);
  for (std::size_t i = 0; i < spec.num_envs; ++i) m.slots[i].base_seed = spec.seed + i;
  const int hw = static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
  const int threads = spec.threads > 0 ? spec.threads : hw;
  m.pool = std::make_unique<StepPool>(
      static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(threads), spec.num_envs)));
  m.scratch.resize(m.pool->threads());
}

VecEnv::~VecEnv() = default;

std::size_t VecEnv::num_envs() const {
  return impl_->slots.size();
}
std::size_t VecEnv::observation_size() const {
  return impl_->obs_size;
}
ActionKind VecEnv::action_kind() const {
  return impl_->spec.actions;
}
const EnvParams& VecEnv::params() const {
  return impl_->params;
}
int VecEnv::lanes() const {
  return impl_->config().road.lane_count;
}
double VecEnv::cruise_speed_mps() const {
  return impl_->cruise_mps();
}

void VecEnv::reset(std::optional<std::uint64_t> seed, float* observation) {
  Impl& m = *impl_;
  if (seed) {
    for (std::size_t i = 0; i < m.slots.size(); ++i) m.slots[i].base_seed = *seed + i;
  }
  m.pool->run(m.slots.size(), [&](std::size_t i, std::size_t /*worker*/) {
    Slot& s = m.slots[i];
    s.status.episode = 0;
    m.begin_episode(s, s.base_seed);
    m.write_observation(s, s.stepper->telemetry(), observation + i * m.obs_size);
  });
  m.reset_done = true;
}

void VecEnv::step(const Actions& actions, const StepOutputs& out) {
  Impl& m = *impl_;
  if (!m.reset_done) throw std::logic_error("step() before reset(): call reset() first");
  m.check_actions(actions);
  m.pool->run(m.slots.size(),
              [&](std::size_t i, std::size_t worker) { m.step_env(i, worker, actions, out); });
}

const EnvStatus& VecEnv::status(std::size_t env) const {
  return impl_->slots.at(env).status;
}

const nlohmann::json& VecEnv::last_report(std::size_t env) const {
  return impl_->slots.at(env).last_report;
}

core::Telemetry VecEnv::telemetry(std::size_t env) const {
  const Slot& s = impl_->slots.at(env);
  if (!s.stepper) throw std::logic_error("telemetry() before reset(): call reset() first");
  return s.stepper->telemetry();
}

nlohmann::json VecEnv::report(std::size_t env) const {
  const Slot& s = impl_->slots.at(env);
  if (!s.stepper) return nullptr;
  return run::report_to_json(s.stepper->report(), s.provenance);
}

}  // namespace overtake::learn
