#pragma once
// Replay files (docs/replay.md): a run recorded step by step for `overtake view`. A preamble
// (magic, version, JSON header) and one zlib stream of records: a frame per step (the ego,
// every car, the referee's running figures), the path of each planner cycle, each incident,
// and the run's report at the end. Positions are fixed-point integers stored as differences
// from the previous frame (version 2), so the records must be read in order from the first.
// The writer streams (deflating as the run goes), the reader checks everything and says what
// is wrong and where. A layer of its own above the simulator: it is fed the run's frames
// (sim::Frame), not the world.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/reference_line.hpp"
#include "overtake/sim/checkpoint.hpp"
#include "overtake/sim/frame.hpp"
#include "overtake/sim/params.hpp"
#include "overtake/sim/referee.hpp"
#include "overtake/sim/run.hpp"

namespace overtake::replay {

inline constexpr std::string_view kReplayMagic = "OVTKRPLY";
/// Version 2: positions as zigzag-varint differences (docs/replay.md). Version 1 (absolute
/// positions) is not read.
inline constexpr std::uint32_t kReplayVersion = 2;
/// Bytes before the header JSON: magic, version, header length.
inline constexpr std::size_t kReplayPreambleBytes = 16;
/// Spacing of the lane lines' points along the reference line (m).
inline constexpr double kReplayLaneLineSpacingM = 5.0;

/// Kinds of records in the body.
enum class ReplayRecordKind : std::uint8_t {
  frame = 1,
  path = 2,
  incident = 3,
  end = 4,
  checkpoint = 5,  ///< added within version 2: a world checkpoint (sim/checkpoint.hpp)
};

/// A replay that cannot be written or read; the message names the file and what is wrong
/// (with the byte offset or the record where it went wrong).
class ReplayError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Where a scenario cut from a run was cut (the header's `provenance.cut_from`).
struct ReplayCutOrigin {
  std::string scenario;  ///< the scenario's name
  std::string replay;    ///< the replay it was cut from, as the cut named it
  std::string policy;    ///< the planner of that run, its traffic and seed
  std::string traffic;
  std::uint64_t seed = 0;
  double at_s = 0.0;     ///< the moment it was cut around (run time)
  double start_s = 0.0;  ///< where the scenario starts
  std::string incident;  ///< the incident near the moment ("" when none)
  friend bool operator==(const ReplayCutOrigin&, const ReplayCutOrigin&) = default;
};

/// What was run (the header's "provenance").
struct ReplayProvenance {
  std::string policy;
  std::string traffic;
  std::uint64_t seed = 1;
  std::string track = "default";  ///< "default" for the built-in track, else the map file
  double duration_s = 0.0;        ///< the duration asked for
  std::string overtake_version;
  std::string config_hash;
  /// A run of a cut scenario: where it was cut from (not in the header otherwise).
  std::optional<ReplayCutOrigin> cut_from;
  friend bool operator==(const ReplayProvenance&, const ReplayProvenance&) = default;
};

/// The header: the road and the limits a viewer needs, and what was run.
struct ReplayHeader {
  double step_s = 0.02;
  int lanes = 3;
  double lane_width_m = 4.0;
  double car_length_m = 0.0;
  double car_width_m = 0.0;
  double speed_limit_mps = 0.0;
  double max_acceleration_mps2 = 0.0;
  double max_jerk_mps3 = 0.0;
  double track_length_m = 0.0;
  /// lanes + 1 closed polylines (d = 0, w, 2w, ...), each flat [x, y, x, y, ...] in metres;
  /// the last point repeats the first.
  std::vector<std::vector<double>> lane_lines;
  std::vector<std::string> incident_types;  ///< names, indexed by the incident records' type
  /// Names of the collision kinds, indexed by a collision record's kind (empty in files
  /// written before collisions were classified).
  std::vector<std::string> collision_kinds;
  ReplayProvenance provenance;
};

/// The header of a run on `line` with `params`: lane lines sampled every 5 m, rounded to cm.
[[nodiscard]] ReplayHeader make_replay_header(const core::ReferenceLine& line,
                                              const sim::WorldParams& params,
                                              ReplayProvenance provenance);
/// The header as the file's JSON text.
[[nodiscard]] std::string replay_header_json(const ReplayHeader& header);
/// The file's uncompressed start: magic, version, header length, header JSON.
[[nodiscard]] std::string replay_preamble(const ReplayHeader& header);

/// One car in a frame (stored: position in cm, yaw in 1e-4 rad, speed in cm/s).
using ReplayCar = sim::CarPose;
/// One step of the run (sim::Frame: what the run's watchers see).
using ReplayFrame = sim::Frame;

/// Turns a run into records (u8 kind, u32 payload length, payload), appended to a buffer.
/// The live view sends these as they are; the writer deflates them. Positions are coded as
/// differences from the previous frame's (and a path's points from the ego and from each
/// other), so one encoder must see the whole run, and its records be read from the first.
class ReplayEncoder {
 public:
  /// A frame, rounded to the stored fixed point. A car whose id is outside [0, 65535] is
  /// clamped into it; a car whose id repeats one before it in the frame, and cars beyond the
  /// 255th, are left out.
  void append_frame(const ReplayFrame& frame, std::string& out);
  /// An incident record for each incident, placed at the ego of the last frame appended.
  void append_incidents(std::span<const sim::Incident> incidents, std::string& out) const;
  /// The path the planner sent at a cycle (at most 65535 points are kept); its first point is
  /// coded against the ego of the last frame appended.
  /// With `exact`, the points as sent follow, bit for bit (for a run of a planner from
  /// outside, whose answers `overtake cut` drives the world with again).
  void append_path(std::span<const core::Vec2> path, std::string& out, bool exact = false) const;
  /// The last record: the run's report as JSON.
  static void append_end(std::string_view report_json, std::string& out);
  /// A checkpoint of the run at the last frame appended (its encoded bytes).
  static void append_checkpoint(std::string_view encoded, std::string& out);

  /// A position as stored: x, y in cm, yaw in 1e-4 rad, speed in cm/s.
  struct Fixed {
    std::int32_t x = 0, y = 0, yaw = 0, speed = 0;
  };
  /// A car of a frame, as stored.
  struct FixedCar {
    int id = 0;
    Fixed at;
  };

 private:
  Fixed ego_;                   // the last frame's ego (zero before the first frame)
  std::vector<FixedCar> cars_;  // the last frame's cars (ids unique)
  std::vector<FixedCar> next_;  // scratch: the frame being written
  std::vector<Fixed> base_;     // scratch: what each car of next_ is coded against
  std::vector<bool> in_frame_;  // scratch: ids already in next_ (65536 flags)
};

/// Streams a replay to `path` while the run goes: records are deflated in chunks and written
/// to `path` + ".partial" (flushed to a readable point about every megabyte of records), and
/// finish() completes the stream and renames the file, so nothing half-written takes the
/// final name. Use it as the run's observer (RunOptions::observer).
/// A path that exists and is not a regular file (/dev/null, a pipe) is written in place.
class ReplayWriter final : public sim::RunObserver {
 public:
  /// Creates the partial file and writes the preamble. Throws ReplayError naming the file.
  ReplayWriter(const std::filesystem::path& path, const ReplayHeader& header);
  /// A recording that was not finished (the run threw) is ended properly: an end record
  /// saying so, the stream completed, the file renamed. Errors are swallowed here.
  ~ReplayWriter() override;
  ReplayWriter(const ReplayWriter&) = delete;
  ReplayWriter& operator=(const ReplayWriter&) = delete;

  void on_frame(const sim::Frame& frame, std::span<const sim::Incident> new_incidents) override;
  void on_path(std::span<const core::Vec2> path) override;
  /// Stores the checkpoint, its info completed from `checkpoint_info` (what was run).
  void on_checkpoint(const sim::Checkpoint& checkpoint) override;
  /// What the run's checkpoints are of (traffic, seed, track, map and config hashes,
  /// policy); the step and time come with each checkpoint.
  void set_checkpoint_info(sim::CheckpointInfo info);
  /// Store each path as sent, bit for bit, besides its centimetres: for a run of a planner
  /// from outside (its state is in no checkpoint), so that `overtake cut` can drive the run on
  /// from a checkpoint with its answers and tell it again what it was told (docs/scenarios.md).
  void set_exact_paths(bool exact);

  /// Writes the end record (the run's report, JSON), completes the stream and gives the file
  /// its name. Throws ReplayError naming the file when anything could not be written (the
  /// partial file is kept). Call once.
  void finish(std::string_view report_json);
  /// Compressed bytes written so far (preamble included).
  [[nodiscard]] std::uint64_t bytes_written() const;
  /// The file being written (the ".partial" name until finish()).
  [[nodiscard]] const std::filesystem::path& partial_path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A path the planner sent; `step` is the frame it belongs to.
struct ReplayPath {
  long step = 0;
  std::vector<core::Vec2> points;
  /// The points as the planner sent them, bit for bit, when the run stored them
  /// (ReplayWriter::set_exact_paths); empty otherwise.
  std::vector<core::Vec2> exact;
  bool has_exact = false;  ///< the record carried them (an empty path has none to carry)
};

/// An incident the referee counted at frame `step`.
struct ReplayIncident {
  long step = 0;
  int type = 0;        ///< index into ReplayHeader::incident_types (IncidentType's order)
  double value = 0.0;  ///< as in the report: mph for speeding, else as Incident::value
  double s_m = 0.0;
  int lane = 0;
  core::Vec2 position;  ///< where the ego was
  /// A collision's class (none in files written before collisions were classified).
  std::optional<sim::CollisionClass> collision;
  /// A collision's contact (its number in the run, from 0; the report's collisions.contacts),
  /// -1 when not known (files written before collisions were counted as contacts).
  long contact = -1;
};

/// A checkpoint the run stored at frame `step`.
struct ReplayCheckpoint {
  long step = 0;
  double t_s = 0.0;
  std::string bytes;  ///< the checkpoint as encoded (sim::decode_checkpoint reads it)
};

/// A whole replay, decoded.
struct Replay {
  ReplayHeader header;
  std::string header_json;
  std::vector<ReplayFrame> frames;
  std::vector<ReplayPath> paths;
  std::vector<ReplayIncident> incidents;
  /// Checkpoints, in step order (none in files written before replays carried them).
  std::vector<ReplayCheckpoint> checkpoints;
  std::string end_json;  ///< the run's report (the `drive --json` keys, without `timing`)
  std::size_t unknown_records = 0;  ///< records of kinds this build does not know (skipped)
};

/// The largest replay file read: a 30-minute drive's replay is 8.4 MB, one of the longest run
/// overtake drives (7 days) about 2.8 GB.
inline constexpr std::uintmax_t kMaxReplayBytes = 4ULL << 30;

/// Reads and checks a replay file. Throws ReplayError naming the file and what is wrong: not
/// a regular file, larger than kMaxReplayBytes, not a replay, another version, a damaged header, a
/// truncated or corrupt body (with the byte offset and the last good record), no end record.
[[nodiscard]] Replay read_replay(const std::filesystem::path& path);
/// The same for bytes already in memory; `name` names them in errors.
[[nodiscard]] Replay parse_replay(std::string_view bytes, std::string_view name);

/// What checking a replay found.
struct ReplayCheck {
  std::string error;        ///< empty when the replay is whole and valid; else as ReplayError's
  std::size_t records = 0;  ///< good records before the fault (all of them when valid)
  std::size_t frames = 0;
  std::size_t incidents = 0;
  std::size_t checkpoints = 0;
  double duration_s = 0.0;  ///< time of the last good frame
};
/// Checks a replay in memory without keeping its records (for `overtake view`).
[[nodiscard]] ReplayCheck check_replay(std::string_view bytes, std::string_view name);

}  // namespace overtake::replay
