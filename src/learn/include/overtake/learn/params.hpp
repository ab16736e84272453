#pragma once
// The learning environment's parameters (config/learn.json; docs/learning.md): how often the
// agent decides, how its observation is scaled, and what its reward counts.

#include <filesystem>
#include <optional>

#include <nlohmann/json.hpp>

namespace overtake::learn {

/// How the observation's numbers are scaled into about [-1, 1].
struct ObservationParams {
  double range_m = 100.0;           ///< cars farther than this (bumper to bumper) are absent
  double speed_scale_mps = 22.352;  ///< speeds over this (50 mph)
  double accel_scale_mps2 = 10.0;   ///< the ego's acceleration over this
  double time_scale_s = 10.0;       ///< the time in the current manoeuvre over this, at most 1
};

/// The reward of one decision: `progress` x the metres driven along the road over those the
/// speed limit would drive in the decision's time (1 at the limit), less each weight x the
/// incidents of its type counted in the decision's steps, `at_fault` more for a collision
/// that was the ego's fault, and `lane_change` for each lane change the agent asked for and
/// the executor began.
struct RewardParams {
  double progress = 1.0;
  double collision = 50.0;
  double at_fault = 50.0;
  double speeding = 5.0;
  double max_acceleration = 5.0;
  double max_jerk = 5.0;
  double outside_lane = 5.0;
  double lane_change = 0.05;
};

struct EnvParams {
  int decision_steps = 10;         ///< world steps per decision (0.2 s at the 0.02 s step)
  double speed_step_mps = 2.2352;  ///< "faster" and "slower" change the target speed by this
  ObservationParams observation;
  RewardParams reward;
  bool terminate_on_collision = true;  ///< a collision ends the episode (terminated)
  int max_path_points = 500;           ///< the most points of a "path" action

  /// Throws run::ConfigError naming the key when a value is out of its range.
  void validate() const;
};

/// The built-in config/learn.json, then the keys of `path` over it (ConfigError naming the
/// file and key for an unknown key, a wrong type or a value out of range).
[[nodiscard]] EnvParams load_env_params(const std::optional<std::filesystem::path>& path);

/// Keys over `p` from a JSON object (the same keys as config/learn.json; `source` names it in
/// errors), validated.
void apply_env_params(EnvParams& p, const nlohmann::json& j, const std::string& source);

/// The parameters as config/learn.json writes them.
[[nodiscard]] nlohmann::json env_params_json(const EnvParams& p);

}  // namespace overtake::learn
