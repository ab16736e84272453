#pragma once
// The referee: the original's rubric of incidents, plus strict comfort figures.

#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/road.hpp"
#include "overtake/core/state_archive.hpp"
#include "overtake/sim/params.hpp"
#include "overtake/sim/safety.hpp"

namespace overtake::sim {

enum class IncidentType { collision, speeding, max_acceleration, max_jerk, outside_lane };
inline constexpr std::size_t kIncidentTypeCount = 5;

/// JSON/report name: collision, speeding, max_acceleration, max_jerk, outside_lane.
[[nodiscard]] std::string_view to_string(IncidentType t);

/// One counted incident.
struct Incident {
  IncidentType type = IncidentType::collision;
  double t_s = 0.0;
  double s_m = 0.0;
  int lane = 0;
  /// What crossed the limit: speed (m/s), acceleration (m/s^2), jerk (m/s^3), d (m; for a
  /// straddle, the d at the moment it counted), or for a collision the other car's id.
  double value = 0.0;
  /// For a collision: its class, decided at the contact's first step (safety.hpp).
  std::optional<CollisionClass> collision;
  /// For a collision: the number of the contact it was counted in (RunReport::contacts), -1
  /// when not known.
  int contact = -1;
  friend bool operator==(const Incident&, const Incident&) = default;
};

/// An incident through a checkpoint.
void archive_incident(core::StateArchive& ar, Incident& incident, int lanes);

/// The ego at the end of one step, as the referee sees it.
struct EgoFrame {
  double t_s = 0.0;
  core::Vec2 position;
  double speed_mps = 0.0;
  double s_m = 0.0;
  double d_m = 0.0;        ///< as the original measures it (waypoint chords): the rubric's
  double exact_d_m = 0.0;  ///< on the reference line: the extra figure
  /// Id of a car whose body touched the ego's this step, if any.
  std::optional<int> collided_with;
  /// The class of that contact (the scorecard's safety monitor decides it) and its number.
  std::optional<CollisionClass> collision;
  int contact = -1;
};

/// Peaks under both rule sets (SI).
struct Peaks {
  double speed_mps = 0.0;
  double acceleration_mps2 = 0.0;         ///< rubric: block-averaged total
  double jerk_mps3 = 0.0;                 ///< rubric: group-averaged
  double strict_acceleration_mps2 = 0.0;  ///< 0.1 s windows
  double strict_jerk_mps3 = 0.0;
  friend bool operator==(const Peaks&, const Peaks&) = default;
};

/// The strict figures at the newest step: finite differences over 0.1 s windows
/// (RefereeParams::strict_window_steps), centred one window back. Zero until enough steps.
struct StrictFigures {
  double tangential_mps2 = 0.0;  ///< along the direction of travel; negative when slowing
  double normal_mps2 = 0.0;      ///< across it (magnitude)
  double acceleration_mps2 =
      0.0;                 ///< total: the figure whose peak is Peaks::strict_acceleration_mps2
  double jerk_mps3 = 0.0;  ///< the figure whose peak is Peaks::strict_jerk_mps3
  friend bool operator==(const StrictFigures&, const StrictFigures&) = default;
};

/// Watches the ego step by step and counts incidents, as the original does: collision,
/// speeding and outside-of-lane latched (counted again while they persist, once per
/// latch_steps); acceleration counted for each block and jerk for each group at or over the
/// limit. The lane rule is applied to the original's d; the same rule on the exact d is
/// counted beside it as a figure (not an incident).
class Referee {
 public:
  Referee(const RefereeParams& params, double step_s, const core::RoadParams& road = {});

  /// The ego's speed before the first step (the rubric's first block compares against it;
  /// the original starts from rest).
  void set_initial_speed(double speed_mps) { prev_block_mean_speed_ = speed_mps; }
  /// Feeds the state after one step. Frames must come once per step, in order.
  void observe(const EgoFrame& frame);
  /// Forgets what was counted (incidents, counts, peaks, distances) and keeps how it counts:
  /// its blocks and groups, latches and recent positions. A cut scenario's referee goes on
  /// from the run's, so that it counts at the same steps as the run did.
  void forget_counts();

  [[nodiscard]] const std::vector<Incident>& incidents() const { return incidents_; }
  [[nodiscard]] std::array<int, kIncidentTypeCount> counts() const;
  /// Outside-of-lane counts under the same rule and latching on the exact d.
  [[nodiscard]] int exact_outside_lane_count() const { return exact_outside_lane_; }
  [[nodiscard]] const Peaks& peaks() const { return peaks_; }
  /// Distance driven (m) since the last incident.
  [[nodiscard]] double incident_free_m() const { return incident_free_m_; }
  /// The longest incident-free stretch so far (m), including the current one.
  [[nodiscard]] double best_incident_free_m() const { return best_incident_free_m_; }
  [[nodiscard]] double distance_m() const { return distance_m_; }
  /// The strict figures at the newest step (computed on demand from the recent positions;
  /// for viewers, it changes nothing the referee counts).
  [[nodiscard]] StrictFigures current_strict() const;

  /// Writes or restores everything it counts and keeps (a checkpoint); the params must be
  /// the same.
  void archive(core::StateArchive& ar);
  /// After a restore: each collision incident gets the number of the contact it was counted
  /// in (the contact with its car whose time span holds it), which a checkpoint does not keep.
  void link_contacts(std::span<const Contact> contacts);

 private:
  void count(IncidentType type, const EgoFrame& f, double value);
  [[nodiscard]] bool latched(IncidentType type) const;
  /// The lane rule on one d: true when it counts (straddle: steps in a line band so far).
  [[nodiscard]] bool outside_lane(double d_m, int& straddle) const;
  /// The position `back` steps before the newest one (0: the newest).
  [[nodiscard]] core::Vec2 recent(long back) const;
  void update_rubric(const EgoFrame& f);
  void update_strict();

  RefereeParams p_;
  double step_s_;
  core::RoadParams road_;
  std::vector<Incident> incidents_;
  Peaks peaks_;
  double distance_m_ = 0.0;
  double incident_free_m_ = 0.0;
  double best_incident_free_m_ = 0.0;
  std::array<long, kIncidentTypeCount> latch_until_step_{};  // may count again from this step
  std::array<int, kIncidentTypeCount> counts_{};
  long step_ = 0;  // index of the frame being observed
  // rubric acceleration: block accumulation (the block's positions are the ring's newest)
  int block_fill_ = 0;
  double block_speed_sum_ = 0.0;
  double prev_block_mean_speed_ = 0.0;  // the original starts from 0
  // rubric jerk: group accumulation of block totals
  int group_fill_ = 0;
  double group_sum_ = 0.0;
  double prev_group_mean_ = 0.0;
  // outside of lane on the exact d
  int exact_outside_lane_ = 0;
  long exact_latch_until_step_ = 0;
  int exact_straddle_steps_ = 0;
  // recent positions for curvature and the strict windows: a ring whose size is a power of
  // two (allocated once), newest at `ring_head_`; `ring_filled_` of them are valid.
  std::vector<core::Vec2> ring_;
  std::size_t ring_mask_ = 0;
  std::size_t ring_head_ = 0;
  long ring_filled_ = 0;
  int straddle_steps_ = 0;
};

}  // namespace overtake::sim
