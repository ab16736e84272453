#pragma once
// Safety beyond the rubric: whose fault each collision was, and how close the ego came to one.
//
// - Every collision is classified at its first contact, from both bodies just before it (the
//   last step at which they did not touch): who was ahead, who was changing lanes, who
//   stood still, whether the ego was braking harder than traffic does. The rules follow
//   nuPlan's at-fault collisions (a stopped ego, or a car driving into the ego's rear, is not
//   the ego's fault; a front contact, a contact with a stopped car, and a side contact while
//   the ego is in two lanes are), with two additions for this world's traffic: a contact
//   within a lane-change window after one of the two bodies entered the other's lane is the
//   fault of the one that entered (RSS's rule that a cut-in must leave the follower room:
//   Shalev-Shwartz et al. 2017), and a rear-end of an ego braking harder than traffic does is
//   the ego's. docs/evaluation.md gives each rule with its thresholds.
// - Near misses, step by step: the constant-velocity time-to-collision (TTC) with the car
//   ahead in the ego's lane and with cars in a lane the ego is entering, and the time
//   headway to the car ahead (SUMO's safety measures, device.ssm); per run, their least
//   values, the time below the thresholds and the near-miss episodes.
//
// Distances are along the road on the map's waypoint chords (s and d as the original
// reports them, as traffic and the rubric measure them), bumper to bumper.

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include "overtake/core/road.hpp"
#include "overtake/core/state_archive.hpp"
#include "overtake/core/waypoint_frenet.hpp"

namespace overtake::sim {

struct TrafficCar;

/// Thresholds of the collision classes and the near-miss figures (config: world.safety).
struct SafetyParams {
  /// A body at or below this speed stands still (nuPlan's stopped-ego threshold).
  double stopped_speed_mps = 0.05;
  /// A mean deceleration over `braking_window_s` above this is harder than traffic brakes:
  /// faithful traffic's 99th percentile of 1-s decelerations, measured (docs/evaluation.md).
  double hard_braking_mps2 = 6.5;
  /// The window of the braking test and of the lateral motion of side contacts.
  double braking_window_s = 1.0;
  /// Whether the body behind could absorb a lane entry: it reacts after this, then brakes
  /// at hard_braking_mps2 (RSS's response time).
  double reaction_time_s = 1.0;
  /// A contact this soon after a body entered the other's lane is that body's lane change.
  double lane_change_window_s = 3.0;
  /// A body is in a lane when its width reaches at least this far into it.
  double lane_overlap_m = 0.3;
  /// Near-miss thresholds: TTC below this, time headway below that.
  double ttc_threshold_s = 1.5;
  double headway_threshold_s = 1.0;
  /// Headway is measured only while the ego moves at least this fast.
  double headway_min_speed_mps = 1.0;
  /// A near-miss episode ends once TTC has stayed at or above the threshold this long.
  double episode_gap_s = 1.0;
  /// A contact with a car ends once the two bodies have been apart this long: touching again
  /// sooner is the same contact (one collision), later a new one.
  double contact_gap_s = 5.0;
  friend bool operator==(const SafetyParams&, const SafetyParams&) = default;
};

/// What kind of collision it was, from the ego's side.
enum class CollisionKind : std::uint8_t {
  ego_hit_car_ahead,        ///< the ego drove into a car ahead in its lane (at fault)
  hit_from_behind,          ///< a car drove into the ego's rear; the ego kept its lane (not)
  hit_from_behind_braking,  ///< likewise, but the ego braked harder than traffic does (at fault)
  ego_lane_change,  ///< the ego changed lanes into a car, or into a gap its follower could not
                    ///< absorb (at fault)
  car_cut_in,       ///< a car changed lanes into the ego (not at fault)
  side_contact,     ///< side by side, neither changing lanes: the fault of the one that closed
  ego_stopped,      ///< contact while the ego stood still (not at fault)
  car_stopped,      ///< the ego drove into a car standing still (at fault)
};
inline constexpr std::size_t kCollisionKindCount = 8;

/// The report's name of a kind ("ego_hit_car_ahead", ...).
[[nodiscard]] std::string_view to_string(CollisionKind kind);

/// A collision's class: its kind and whether the ego was at fault.
struct CollisionClass {
  CollisionKind kind = CollisionKind::ego_hit_car_ahead;
  bool at_fault = true;
  friend bool operator==(const CollisionClass&, const CollisionClass&) = default;
};

/// One body just before a contact, as the classification reads it.
struct ContactBody {
  core::FrenetPoint frenet;  ///< s and d on the waypoint chords
  double speed_mps = 0.0;
  bool in_two_lanes = false;  ///< its width reaches into two lanes (changing lanes)
  /// How far its d moved toward the other body over the braking window (m; negative: away).
  double toward_other_m = 0.0;
};

/// Both bodies at the step one of them entered the lane the other is in (its width first
/// reached into it): the newest lane it entered.
struct LaneEntry {
  /// Seconds from the end of that lane change (its body no longer in two lanes) to the
  /// contact, 0 while it is still crossing; infinity: it did not enter that lane (it was in
  /// it from the run's start or its own placement, or the lane is not its newest).
  double s_ago = std::numeric_limits<double>::infinity();
  /// Seconds from the entry itself (its body first in the lane) to the contact.
  double entered_s_ago = std::numeric_limits<double>::infinity();
  core::FrenetPoint ego;  ///< on the waypoint chords, then
  core::FrenetPoint car;
  double ego_speed_mps = 0.0;
  double car_speed_mps = 0.0;
};

/// Both bodies just before their first contact.
struct ContactSituation {
  ContactBody ego;
  ContactBody car;
  LaneEntry ego_entry;  ///< the ego entering the car's lane
  LaneEntry car_entry;  ///< the car entering the ego's lane
  /// The ego's mean deceleration over the braking window (m/s^2; negative when speeding up).
  double ego_deceleration_mps2 = 0.0;
  double loop_length_m = 0.0;  ///< s wraps at this
  core::CarFootprint size;     ///< every body's footprint
};

/// The class of a contact (docs/evaluation.md, "Whose fault").
[[nodiscard]] CollisionClass classify_collision(const ContactSituation& situation,
                                                const SafetyParams& params);

/// True when the body behind at a lane entry could have kept clear of the one ahead, given
/// what the one ahead did from the entry to the contact (RSS's proper response, Shalev-Shwartz
/// et al. 2017): reacting after `reaction_time_s` at its speed and then braking at
/// `hard_braking_mps2`, it would have stopped closing before the gap was gone while the one
/// ahead slowed from its entry speed at its mean deceleration until the contact
/// (`front_speed_now_mps` is its speed just before the contact). A front body that slowed
/// harder than traffic brakes left no room the one behind was owed: not absorbable; nor an
/// entry beside the other (no gap).
[[nodiscard]] bool entry_absorbable(const LaneEntry& entry, double front_speed_now_mps,
                                    double loop_length_m, const core::CarFootprint& size,
                                    const SafetyParams& params);

/// Constant-velocity time-to-collision (s) of a follower closing on a leader `gap_m` ahead
/// (bumper to bumper): gap / (follower - leader speed) when it closes, else infinity.
[[nodiscard]] double time_to_collision_s(double gap_m, double follower_speed_mps,
                                         double leader_speed_mps);

/// The near-miss figures at one step (infinity: no such car, or not closing).
struct SafetyFigures {
  double ttc_ahead_s = std::numeric_limits<double>::infinity();
  double ttc_entering_s = std::numeric_limits<double>::infinity();
  double headway_s = std::numeric_limits<double>::infinity();
  friend bool operator==(const SafetyFigures&, const SafetyFigures&) = default;
};

/// A run's near-miss figures (infinity where never measured).
struct SafetySummary {
  double min_ttc_ahead_s = std::numeric_limits<double>::infinity();
  double min_ttc_entering_s = std::numeric_limits<double>::infinity();
  double min_headway_s = std::numeric_limits<double>::infinity();
  double ttc_below_s = 0.0;      ///< time with either TTC below the threshold
  double headway_below_s = 0.0;  ///< time with the headway below the threshold
  int near_miss_episodes = 0;    ///< episodes of TTC below the threshold without a contact
  double ttc_threshold_s = 0.0;
  double headway_threshold_s = 0.0;
  friend bool operator==(const SafetySummary&, const SafetySummary&) = default;
};

/// The ego as the monitor sees it after a step.
struct SafetyEgo {
  core::FrenetPoint frenet;  ///< on the waypoint chords
  double speed_mps = 0.0;
};

/// A step at which a car touches the ego, as the monitor sees it: which contact it belongs
/// to and that contact's class.
struct ContactStep {
  CollisionClass collision;  ///< decided at the contact's first step, held while it lasts
  int index = 0;             ///< the contact's number in the run (0, 1, ...)
  bool begins = false;       ///< this is the contact's first step
};

/// One contact of the ego with one car, as a run reports it: a collision as evaluation counts
/// them (the rubric counts a collision incident for every second of contact).
struct Contact {
  int car_id = -1;
  double t_s = 0.0;      ///< its first step
  double end_t_s = 0.0;  ///< the last step at which the two touched
  double s_m = 0.0;      ///< the ego's s at its first step (on the waypoint chords)
  int lane = 0;          ///< the ego's lane then
  CollisionClass collision;
  /// The rubric's collision incidents counted while it lasted (0 when the rubric's latch still
  /// held from a contact with another car).
  int rubric_collisions = 0;
  friend bool operator==(const Contact&, const Contact&) = default;
};

/// Watches the ego and the cars step by step: groups the steps at which a car touches the ego
/// into contacts (one car; it ends once the two have been apart for `contact_gap_s`),
/// classifies each contact once, at its start, and measures TTC and headway.
class SafetyMonitor {
 public:
  SafetyMonitor(const SafetyParams& params, double step_s, const core::RoadParams& road,
                const core::CarFootprint& size, double loop_length_m);

  /// After each step: the ego, the cars, and the car touching the ego (if any). Returns the
  /// contact that car's touch belongs to (classified when it began).
  std::optional<ContactStep> observe(const SafetyEgo& ego, std::span<const TrafficCar> cars,
                                     std::optional<int> contact_id);

  /// The figures at the newest step.
  [[nodiscard]] const SafetyFigures& current() const { return current_; }
  /// The run so far.
  [[nodiscard]] SafetySummary summary() const;
  /// Contacts begun so far.
  [[nodiscard]] int contacts_begun() const { return contacts_begun_; }
  /// Forgets what was counted (the summary, near-miss episodes, contacts) and keeps the tracks
  /// (each body's lanes and when it entered them, its recent states): a cut scenario's monitor
  /// goes on from the run's, so that a contact is classified as in the run. A contact going on
  /// at the start is forgotten (its next touch begins one).
  void forget_counts();

  /// Writes or restores its tracks, figures and episodes (a checkpoint).
  void archive(core::StateArchive& ar);
  /// Writes or restores the contacts that have not ended (a part of its own, added after the
  /// checkpoint's first format: a checkpoint without it restores with none open).
  void archive_contacts(core::StateArchive& ar);

 private:
  /// One step of a body's history.
  struct Sample {
    core::FrenetPoint frenet;
    double speed_mps = 0.0;
  };
  static constexpr std::size_t kMaxLanes = 8;
  /// A car at the step the ego entered a lane.
  struct CarAt {
    int id = -1;
    Sample at;
  };
  /// A body's history: its lanes since when, the states at its lane entries, and its
  /// states over the braking window.
  struct Track {
    bool active = false;
    int id = -1;
    std::array<long, kMaxLanes>
        lane_since{};          ///< step its body entered each lane (or kNotIn, kAlways)
    long two_lanes_last = -1;  ///< the last step its body was in two lanes
    int span_lo = 0;           ///< the lanes its body is in: span_lo..span_hi (none: lo > hi)
    int span_hi = -1;
    bool entered_now = false;                    ///< it entered a lane in this step
    std::array<Sample, kMaxLanes> entry_self{};  ///< itself at each lane entry
    std::array<Sample, kMaxLanes> entry_ego{};   ///< a car: the ego at each of its lane entries
    std::array<std::vector<CarAt>, kMaxLanes> entry_cars;  ///< the ego: the cars at its entries
    std::vector<Sample> ring;  ///< the window's states (newest at ring_head_)
  };

  void update_track(Track& t, core::FrenetPoint at, double speed_mps, bool appeared);
  /// Keeps the states at the lane entries made in this step.
  void note_entries();
  /// The sample `back` steps before the newest.
  [[nodiscard]] const Sample& sample(const Track& t, long back) const;
  [[nodiscard]] LaneEntry lane_entry(const Track& mover, const Track& other,
                                     bool mover_is_ego) const;
  /// Classifies the contact with `car_id` from the tracks as they are; false when that car
  /// has no track (not on the road).
  bool classify_contact(int car_id);
  [[nodiscard]] ContactBody contact_body(const Track& self, const Track& other) const;
  /// The lanes a body at `d_m` is in, as [first, last] (none: first > last).
  [[nodiscard]] std::pair<int, int> lane_span(double d_m) const;
  [[nodiscard]] double wrapped_ds(double from_s, double to_s) const;
  /// TTC and headway from the tracks as they are now.
  void measure();
  void count_episode(bool below, bool contact);
  void archive_track(core::StateArchive& ar, Track& t, bool is_ego);

  SafetyParams p_;
  double step_s_;
  core::RoadParams road_;
  core::CarFootprint size_;
  double loop_length_m_;
  long window_steps_;  ///< the braking window in steps
  double inverse_lane_width_ = 0.0;
  long step_ = 0;             ///< the step being observed (0: the start)
  long last_step_ = 0;        ///< the step the tracks hold
  bool entries_now_ = false;  ///< some body entered a lane in this step
  std::size_t ring_head_ = 0;
  Track ego_;
  std::vector<Track> cars_;  ///< by index in the traffic's list
  /// A contact that has not ended: its car, the last step they touched, its class and number.
  struct OpenContact {
    int car_id = -1;
    long last_step = 0;
    CollisionClass collision;
    int index = 0;
  };
  std::optional<int> contact_id_;  ///< the car that touched the ego at the newest step
  CollisionClass contact_class_;   ///< its contact's class
  std::vector<OpenContact> open_contacts_;
  int contacts_begun_ = 0;
  long contact_gap_steps_ = 1;
  SafetyFigures current_;
  SafetySummary summary_;
  // near-miss episodes
  bool in_episode_ = false;
  bool episode_contact_ = false;
  long last_below_step_ = 0;
};

}  // namespace overtake::sim
