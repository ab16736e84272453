#include "overtake/sim/checkpoint.hpp"

#include <limits>

namespace overtake::sim {
namespace {

/// A run's state is a few kilobytes; a week-long run's incidents could make it megabytes.
constexpr std::size_t kMaxPartBytes = std::size_t{1} << 30U;
constexpr std::size_t kMaxText = 4096;

void archive_info(core::StateArchive& ar, CheckpointInfo& info) {
  ar.part("info");
  ar.io_range(info.step, 0, std::numeric_limits<long>::max() / 2, "step");
  ar.io(info.t_s, "time");
  ar.io(info.traffic, kMaxText, "traffic");
  ar.require(info.traffic == "faithful" || info.traffic == "calm" || info.traffic == "scripted",
             "traffic: '" + info.traffic + "' is none of faithful, calm, scripted");
  ar.io(info.seed, "seed");
  ar.io(info.track, kMaxText, "track");
  ar.io(info.map_hash, kMaxText, "map hash");
  ar.io(info.config_hash, kMaxText, "config hash");
  ar.io(info.policy, kMaxText, "policy");
}

}  // namespace

std::string encode_checkpoint(const Checkpoint& checkpoint) {
  core::StateArchive ar;
  ar.magic(kCheckpointMagic, "a checkpoint");
  std::uint32_t version = kCheckpointVersion;
  ar.io(version, "version");
  Checkpoint c = checkpoint;
  archive_info(ar, c.info);
  ar.part("parts");
  ar.io(c.run, kMaxPartBytes, "run state");
  ar.io(c.planner, kMaxPartBytes, "planner state");
  return ar.take();
}

Checkpoint decode_checkpoint(std::string_view bytes, std::string_view name) {
  core::StateArchive ar(bytes, std::string(name));
  ar.magic(kCheckpointMagic, "a checkpoint");
  std::uint32_t version = 0;
  ar.io(version, "version");
  ar.require(version == kCheckpointVersion,
             "checkpoint version " + std::to_string(version) + ", this build reads version " +
                 std::to_string(kCheckpointVersion) + " (cut the scenario again from its replay)");
  Checkpoint c;
  archive_info(ar, c.info);
  ar.part("parts");
  ar.io(c.run, kMaxPartBytes, "run state");
  ar.io(c.planner, kMaxPartBytes, "planner state");
  ar.expect_end();
  return c;
}

}  // namespace overtake::sim
