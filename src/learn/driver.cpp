#include "overtake/learn/driver.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "overtake/learn/command.hpp"
#include "overtake/planner/reference/reference_policy.hpp"

namespace overtake::learn {

using planner::reference::DrivingCommand;
using planner::reference::ReferencePolicy;

PolicyDriver::PolicyDriver(const core::ReferenceLine& line, double loop_length_m,
                           const run::Config& config, const EnvParams& params, ActionKind kind)
    : config_(config),
      params_(params),
      kind_(kind),
      loop_length_m_(loop_length_m),
      executor_(std::make_unique<ReferencePolicy>(line, config.planner)) {
  if (kind == ActionKind::path) {
    throw std::invalid_argument(
        "a policy of paths gives its paths itself: drive it as a Python planner");
  }
  params_.validate();
  ego_.target_speed_mps = config.planner.reference.behaviour.cruise_speed_mps;
}

PolicyDriver::~PolicyDriver() = default;

// World steps since the last call: the points of the path sent then that the world has taken.
namespace {
long consumed(std::size_t sent, const core::Telemetry& t) {
  return sent > t.previous_path.size() ? static_cast<long>(sent - t.previous_path.size()) : 0;
}
}  // namespace

bool PolicyDriver::decision_due(const core::Telemetry& t) const {
  return !started_ || since_steps_ + consumed(sent_, t) >= params_.decision_steps;
}

std::size_t PolicyDriver::observation_size() const {
  return learn::observation_size(config_.road.lane_count);
}

void PolicyDriver::observe(const core::Telemetry& t, std::span<float> out) const {
  EgoContext e = ego_;
  if (!started_) {
    e.target_lane =
        std::clamp(core::lane_of(t.ego.d_m, config_.road), 0, config_.road.lane_count - 1);
  }
  const long since = since_steps_ + consumed(sent_, t);
  const double step_s = config_.world.step_s;
  e.accel_mps2 = since > 0 ? (t.ego.speed_mps - speed_at_decision_mps_) / (since * step_s) : 0.0;
  e.manoeuvre_s = static_cast<double>(since_lane_steps_ + consumed(sent_, t)) * step_s;
  learn::observe(t, e, config_.road, loop_length_m_, config_.car.length_m, params_.observation,
                 out);
}

core::PlanResult PolicyDriver::plan(const core::Telemetry& t, const std::int64_t* meta,
                                    const float* continuous) {
  const long steps = consumed(sent_, t);
  since_steps_ += steps;
  since_lane_steps_ += steps;
  const int lanes = config_.road.lane_count;
  if (!started_) {
    ego_.target_lane = std::clamp(core::lane_of(t.ego.d_m, config_.road), 0, lanes - 1);
    started_ = true;
  }
  const int lane_before = ego_.target_lane;
  const double cruise = config_.planner.reference.behaviour.cruise_speed_mps;
  if (kind_ == ActionKind::meta && meta != nullptr) {
    if (*meta < 0 || *meta >= kMetaActions) {
      throw std::invalid_argument(
          "the policy's action is " + std::to_string(*meta) +
          ": a meta-action is 0 keep, 1 left, 2 right, 3 faster or 4 slower");
    }
    apply_meta(ego_, *meta, lanes, cruise, params_.speed_step_mps);
  } else if (kind_ == ActionKind::continuous && continuous != nullptr) {
    if (!(continuous[0] >= 0.0F && continuous[0] <= 1.0F) ||
        !(continuous[1] >= -1.0F && continuous[1] <= 1.0F)) {
      throw std::invalid_argument(
          "the policy's action is out of range: [target speed in 0..1, target lane in -1..1]");
    }
    apply_continuous(ego_, continuous[0], continuous[1], lanes, cruise);
  }
  if (meta != nullptr || continuous != nullptr) {
    since_steps_ = 0;
    speed_at_decision_mps_ = t.ego.speed_mps;
  }
  executor_->set_command(DrivingCommand{ego_.target_lane, ego_.target_speed_mps});
  core::PlanResult plan = executor_->plan(t);
  // A lane change the trajectory layer did not take is dropped, as in the environment.
  const int end_lane = executor_->last_plan().trajectory.end_lane;
  if (end_lane != ego_.target_lane) ego_.target_lane = end_lane;
  if (ego_.target_lane != lane_before) since_lane_steps_ = 0;
  sent_ = plan.path.size();
  return plan;
}

}  // namespace overtake::learn
