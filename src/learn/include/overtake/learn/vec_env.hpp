#pragma once
// The learning environment (docs/learning.md): N worlds stepped together, one decision each
// per call, on threads of its own; arrays in and out. An agent decides by meta-actions (keep,
// change left or right, faster, slower) or a continuous target (speed, lane) that the
// reference planner's prediction and trajectory layers carry out, or gives the raw path.
// Every episode is a drive with the drive's scorecard, so a learned policy is judged as any
// other planner is. Deterministic: the same seeds and actions give the same arrays, whatever
// the number of threads, and env i of N is env 0 of one seeded seed + i.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/core/telemetry.hpp"
#include "overtake/learn/params.hpp"

namespace overtake::learn {

/// How an agent acts.
enum class ActionKind : std::uint8_t {
  meta,        ///< one of kMetaActions integers a decision (MetaAction)
  continuous,  ///< two floats a decision: target speed in [0, 1] of the cruise speed, lane in [-1,
               ///< 1]
  path,        ///< the raw path: up to max_path_points (x, y) map points, NaN rows ending it
};

/// "meta", "continuous", "path"; std::invalid_argument naming the three otherwise.
[[nodiscard]] ActionKind parse_action_kind(std::string_view text);
[[nodiscard]] std::string_view to_string(ActionKind kind);

/// The meta-actions, as integers.
enum MetaAction : std::uint8_t { keep = 0, left = 1, right = 2, faster = 3, slower = 4 };
inline constexpr int kMetaActions = 5;

struct VecEnvSpec {
  std::size_t num_envs = 1;
  std::uint64_t seed = 0;  ///< env i's episodes are drawn from seed + i
  ActionKind actions = ActionKind::meta;
  std::optional<std::filesystem::path> map;     ///< none: the built-in track
  std::optional<std::filesystem::path> config;  ///< the world's and planner's parameters
  std::optional<std::filesystem::path> params;  ///< the environment's (config/learn.json keys)
  std::string traffic = "faithful";
  double minutes = 5.0;        ///< an episode's length (truncated there)
  int threads = 0;             ///< 0: one per hardware thread, at most num_envs
  std::string name = "agent";  ///< the policy's name in the episodes' reports
};

/// One call's actions, for every env (the kind the environment was made with).
struct Actions {
  const std::int64_t* meta = nullptr;  ///< num_envs
  const float* continuous = nullptr;   ///< num_envs x 2
  const double* path = nullptr;        ///< num_envs x path_points x 2
  std::size_t path_points = 0;
};

/// Where one call writes, for every env.
struct StepOutputs {
  float* observation = nullptr;  ///< num_envs x observation_size()
  float* reward = nullptr;       ///< num_envs
  std::uint8_t* terminated = nullptr;
  std::uint8_t* truncated = nullptr;
};

/// An env's figures after the last call.
struct EnvStatus {
  std::uint64_t episode_seed = 0;
  long episode = 0;        ///< episodes begun (1 after the first reset)
  bool was_reset = false;  ///< this call began a new episode (its action was not taken)
  double time_s = 0.0;     ///< simulated time in the episode
  double distance_m = 0.0;
  double speed_mps = 0.0;
  int lane = 0;
  int target_lane = 0;
  double target_speed_mps = 0.0;
  double episode_return = 0.0;  ///< rewards so far in the episode
  long episode_length = 0;      ///< decisions so far in the episode
  std::size_t collisions = 0;   ///< in the episode
  std::size_t at_fault = 0;
  std::size_t incidents = 0;  ///< every type
};

class VecEnv {
 public:
  /// Loads the map, config and params and makes the worlds (not yet reset). Throws
  /// std::invalid_argument for a bad spec (naming the field), run::ConfigError or
  /// core::MapError for files that cannot be used.
  explicit VecEnv(const VecEnvSpec& spec);
  ~VecEnv();
  VecEnv(const VecEnv&) = delete;
  VecEnv& operator=(const VecEnv&) = delete;

  [[nodiscard]] std::size_t num_envs() const;
  [[nodiscard]] std::size_t observation_size() const;
  [[nodiscard]] ActionKind action_kind() const;
  [[nodiscard]] const EnvParams& params() const;
  [[nodiscard]] int lanes() const;
  [[nodiscard]] double cruise_speed_mps() const;

  /// Begins an episode in every env (with `seed`: env i's seeds start again from seed + i)
  /// and writes their observations.
  void reset(std::optional<std::uint64_t> seed, float* observation);

  /// One decision in every env, on the environment's threads (the caller's among them).
  /// An env whose episode ended at the last call begins its next episode instead (its action
  /// is not taken; reward 0, neither terminated nor truncated): Gymnasium's next-step
  /// autoreset. Throws std::invalid_argument naming the env and value for an action out of
  /// range (a meta-action not in 0..4, a continuous value outside its range or not finite, a
  /// path point not finite) before any world steps; std::logic_error before reset().
  void step(const Actions& actions, const StepOutputs& out);

  [[nodiscard]] const EnvStatus& status(std::size_t env) const;
  /// The report of env's last finished episode, as `overtake drive --json` writes it (null
  /// before one has ended).
  [[nodiscard]] const nlohmann::json& last_report(std::size_t env) const;
  /// What env's planner is told now (the observation's source).
  [[nodiscard]] core::Telemetry telemetry(std::size_t env) const;
  /// The report of env's episode so far.
  [[nodiscard]] nlohmann::json report(std::size_t env) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace overtake::learn
