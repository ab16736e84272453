#pragma once
// World checkpoints: the whole state of a run at a planner cycle's start (docs/scenarios.md).
// The run's part (the world with its traffic model, the scorecard, the stepper) restores
// exactly: a run restored from a checkpoint taken at step N and run on reports the same, byte
// for byte, as the run that never stopped. The planner's part is its own (a built-in policy
// keeps its state there; a planner from outside keeps state overtake cannot see, and its part
// is empty).

#include <cstdint>
#include <string>
#include <string_view>

#include "overtake/core/state_archive.hpp"

namespace overtake::sim {

inline constexpr std::string_view kCheckpointMagic = "OVTKCKPT";
/// Bumped whenever a part's fields change: a checkpoint of another version is refused.
inline constexpr std::uint32_t kCheckpointVersion = 1;
/// No checkpoint is of a run longer than this (about 11.6 days; the longest drive is a week).
/// A state past it is refused: restoring it would mean catching up that much traffic.
inline constexpr double kMaxCheckpointRunS = 1e6;

/// What a checkpoint is of, so that it is restored into a world made the same way.
struct CheckpointInfo {
  long step = 0;
  double t_s = 0.0;
  std::string traffic;      ///< "faithful", "calm" or "scripted"
  std::uint64_t seed = 0;   ///< the run's seed (for the record: the streams are in the state)
  std::string track;        ///< "default" or the map file
  std::string map_hash;     ///< of the map's waypoints
  std::string config_hash;  ///< of the parameters the run used
  std::string policy;       ///< the planner that drove ("" when unknown)
  friend bool operator==(const CheckpointInfo&, const CheckpointInfo&) = default;
};

/// A checkpoint: what it is of, the run's state and the planner's.
struct Checkpoint {
  CheckpointInfo info;
  std::string run;      ///< world, scorecard and stepper (Stepper::save)
  std::string planner;  ///< the planner's own state; empty when it keeps none overtake sees
  friend bool operator==(const Checkpoint&, const Checkpoint&) = default;
};

/// The checkpoint as bytes: magic, version, then the info and both parts (lengths first).
[[nodiscard]] std::string encode_checkpoint(const Checkpoint& checkpoint);
/// Reads and checks the bytes; throws core::StateError naming `name` and what is wrong (not
/// a checkpoint, another version, truncated, lengths out of range). The parts themselves are
/// checked when they are restored.
[[nodiscard]] Checkpoint decode_checkpoint(std::string_view bytes, std::string_view name);

}  // namespace overtake::sim
