#pragma once
// What the trajectory files share: trajectory.cpp (the plan: ranking the combinations, the
// checked search, the fallback and the least-bad search), trajectory_candidates.cpp (lanes in
// play, the along-road scale, cars per lane, the lateral and longitudinal candidates and the
// soft lane costs) and trajectory_checks.cpp (the collision and Cartesian checks over
// samples). Not part of the planner's interface (overtake/planner/reference/trajectory.hpp is).
//
// s is the reference line's arc length; on a bend a lane's centre runs longer or shorter than
// the line, so a quantity in units of s is turned into metres along the road by a scale in
// metres of road per unit of s (`m_per_unit_s`): ds/dt (units of s per second) times it is a
// speed in m/s.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <vector>

#include "overtake/core/road.hpp"
#include "overtake/planner/params.hpp"
#include "overtake/planner/reference/frenet.hpp"
#include "overtake/planner/reference/polynomial.hpp"
#include "overtake/planner/reference/prediction.hpp"
#include "overtake/planner/reference/trajectory.hpp"

namespace overtake::planner::reference::trajectory_detail {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// Samples before t = 0, so that the 0.1 s windows at the start see the start state's
/// continuation.
constexpr int kBack = 3;
/// The ego never reverses: a planned ds/dt below this is refused.
constexpr double kReverseTolerance = -1e-4;
/// A gentle stop (to standstill behind a stopped car, or at a crawl): its braking and jerk.
constexpr double kGentleStopMps2 = 2.0;
constexpr double kGentleStopJerkMps3 = 2.5;
/// Off its lane's centre by more than this, the ego counts as moving across lanes.
constexpr double kSidewaysM = 0.5;

// ---- Sampling (the checks' grid) ----

/// Samples of one motion over the grid k = -kBack .. n (index k + kBack).
struct Track1d {
  std::vector<double> x;
  std::vector<double> v;
};

/// Buffers to reuse (see TrajectoryScratch).
using SpareBuffers = std::vector<std::vector<double>>;

/// A buffer from `spare` (its contents whatever they were), or a new one.
[[nodiscard]] inline std::vector<double> take_buffer(SpareBuffers& spare) {
  if (spare.empty()) return {};
  std::vector<double> out = std::move(spare.back());
  spare.pop_back();
  return out;
}

/// Empty samples with buffers from `spare`.
[[nodiscard]] inline Track1d take_track(SpareBuffers& spare) {
  Track1d t;
  t.x = take_buffer(spare);
  t.v = take_buffer(spare);
  return t;
}

/// The check grid: step h over the horizon, n steps.
struct Grid {
  double h = 0.1;
  int n = 50;
  [[nodiscard]] std::size_t size() const { return static_cast<std::size_t>(n + 1 + kBack); }
  [[nodiscard]] double t(int k) const { return h * k; }
};

[[nodiscard]] inline Grid grid_of(const ReferenceTrajectoryParams& p) {
  Grid g;
  g.h = p.check_step_s;
  g.n = std::max(1, static_cast<int>(std::lround(p.horizon_s / p.check_step_s)));
  return g;
}

/// `motion_at(t)` sampled over the grid.
template <class F>
[[nodiscard]] Track1d sample(const Grid& g, F&& motion_at) {
  Track1d out;
  out.x.resize(g.size());
  out.v.resize(g.size());
  for (int k = -kBack; k <= g.n; ++k) {
    const Motion1d m = motion_at(g.t(k));
    out.x[static_cast<std::size_t>(k + kBack)] = m.x;
    out.v[static_cast<std::size_t>(k + kBack)] = m.v;
  }
  return out;
}

/// `motion_at(t)` sampled over the grid into `out` if it stays within the limits along one
/// axis (no reversing for s) from t = 0 on; false (and `out` unfinished) at the first sample
/// over one. Each grid time is evaluated once, for the check and the samples both.
template <class F>
[[nodiscard]] bool sample_within(const Grid& g, F&& motion_at, double max_accel, double max_jerk,
                                 bool forward, Track1d& out) {
  out.x.resize(g.size());
  out.v.resize(g.size());
  for (int k = -kBack; k <= g.n; ++k) {
    const Motion1d m = motion_at(g.t(k));
    if (k >= 0) {
      if (forward && m.v < kReverseTolerance) return false;
      if (std::abs(m.a) > max_accel || std::abs(m.j) > max_jerk) return false;
    }
    out.x[static_cast<std::size_t>(k + kBack)] = m.x;
    out.v[static_cast<std::size_t>(k + kBack)] = m.v;
  }
  return true;
}

/// A longitudinal motion's `at`, with a polynomial's end state worked out once.
struct LongitudinalSampler {
  const Longitudinal& m;
  Motion1d end = m.braking ? Motion1d{} : m.poly.raw(m.poly.duration_s);
  [[nodiscard]] Motion1d operator()(double t) const {
    return m.braking ? m.brake.at(t) : m.poly.at(t, end);
  }
};

/// A polynomial's `at`, its end state worked out once.
struct PolynomialSampler {
  const Polynomial1d& p;
  Motion1d end = p.raw(p.duration_s);
  [[nodiscard]] Motion1d operator()(double t) const { return p.at(t, end); }
};

/// One predicted car over the grid (k = 0 .. n).
struct CarSamples {
  CarSamples() = default;
  // Moved, the views keep pointing into the buffer that moves with them; a copy's would not.
  CarSamples(CarSamples&&) noexcept = default;
  CarSamples& operator=(CarSamples&&) noexcept = default;
  CarSamples(const CarSamples&) = delete;
  CarSamples& operator=(const CarSamples&) = delete;
  ~CarSamples() = default;

  /// `n` samples of each, in one allocation.
  void resize(std::size_t n) {
    buffer.assign(4 * n, 0.0);
    s = {buffer.data(), n};
    s_dot = {buffer.data() + n, n};
    d = {buffer.data() + 2 * n, n};
    d_dot = {buffer.data() + 3 * n, n};
  }

  int id = 0;
  double cap_mps = 0.0;                  // estimated speed cap
  bool speeding_up = false;              // accelerating now: not a car that brakes for the ego
  std::span<double> s, s_dot, d, d_dot;  // k = 0 .. n, views of `buffer`
  std::vector<double> buffer;
};

// ---- The checks (trajectory_checks.cpp) ----

/// The cars within reach of `s0` along the road, predicted from `delay` after their
/// observation, over the grid (their buffers from `spare` where given).
[[nodiscard]] std::vector<CarSamples> sample_cars(const std::vector<CarPrediction>& cars,
                                                  double delay, double s0, const Grid& g,
                                                  SpareBuffers* spare = nullptr);

/// The collision check over samples (indexed k + kBack). `ego_changing`: the ego moves into
/// another lane; `sideways`: it is off its lane's centre or moving into another lane.
[[nodiscard]] CollisionReport collide(const Track1d& lon, const Track1d& lat, bool ego_changing,
                                      bool sideways, const Grid& g,
                                      const std::vector<CarSamples>& cars, double m_per_unit_s,
                                      const ReferenceParams& p, const core::CarFootprint& car);

/// The Cartesian check over samples; before t = 0, the positions driven (`history`, newest
/// first) where given. `stop_at_first`: return at the first sample over a limit (then only
/// `ok` and `first_violation_s` are the whole check's; the peaks leave samples out).
[[nodiscard]] KinematicReport kinematics(const Track1d& lon, const Track1d& lat, const Grid& g,
                                         const LaneFrame& line, const ReferenceTrajectoryParams& p,
                                         bool stop_at_first,
                                         const std::vector<FrenetState>& history = {});

// ---- The candidates (trajectory_candidates.cpp) ----

/// The lanes in play: behaviour's (`target_lane`), the one the ego is in (to stay or return),
/// and on a lane line both lanes of that line (to finish or undo a change); in that order.
[[nodiscard]] std::vector<int> lanes_in_play(const FrenetState& x0, int target_lane,
                                             double line_band_m, const core::RoadParams& road);

/// The along-road scale over the stretch ahead, in the lanes in play and where the ego is.
struct AlongRoadScale {
  double m_per_unit_s = 1.0;  ///< the smallest: metres of road per unit of s, s to metres
  double s_dot_cap = 0.0;     ///< the wanted speed (within the limit) as ds/dt at the largest
};

[[nodiscard]] AlongRoadScale along_road_scale(const LaneFrame& line, const FrenetState& x0,
                                              double wanted_speed_mps,
                                              const std::vector<int>& lanes,
                                              const ReferenceTrajectoryParams& tp,
                                              const core::RoadParams& road);

/// The cars of one lane: the nearest two ahead, the nearest behind, and the leader's
/// prediction. Pointers into the samples and predictions they were found in.
struct LaneCars {
  std::vector<const CarSamples*> ahead;
  const CarSamples* behind = nullptr;
  const CarPrediction* leader = nullptr;
};

/// The cars of each lane in play (indexed by lane; the other lanes' are empty). `samples` are
/// `cars` over the grid; `s0_m` is where the ego starts.
[[nodiscard]] std::vector<LaneCars> cars_per_lane(const std::vector<int>& lanes,
                                                  const std::vector<CarSamples>& samples,
                                                  const std::vector<CarPrediction>& cars,
                                                  double s0_m, const core::RoadParams& road);

/// The leaders of the lanes in play, each once, in the lanes' order.
[[nodiscard]] std::vector<const CarPrediction*> lane_leaders(
    const std::vector<int>& lanes, const std::vector<LaneCars>& lane_cars);

/// A lateral candidate: a quintic to a lane's centre, sampled, with its cost.
struct LatCandidate {
  Polynomial1d poly;
  Track1d samples;
  int end_lane = 0;
  double cost = 0.0;        // the sum of the lateral terms of `terms`, as added
  TrajectoryCost terms;     // lateral_jerk, lateral_time, off_target_lane, linger
  double overstay_s = 0.0;  // when it would have lingered on a lane line too long (or infinity)
};

/// Lateral candidates: to the centre of each lane in play, over the lateral time factors,
/// within the axis limits and on the road. One that would linger on a lane line costs so much
/// that it is driven only when nothing else is safe.
[[nodiscard]] std::vector<LatCandidate> lateral_candidates(const std::vector<int>& lanes,
                                                           const TrajectoryRequest& req,
                                                           const Grid& g, const LaneFrame& line,
                                                           const ReferenceTrajectoryParams& tp,
                                                           const core::RoadParams& road,
                                                           SpareBuffers& spare);

/// A longitudinal candidate, sampled, with its cost.
struct LonCandidate {
  Longitudinal motion;
  Track1d samples;
  double cost = 0.0;     // the sum of the longitudinal terms of `terms`, as added
  TrajectoryCost terms;  // progress, longitudinal_jerk
};

/// The braking fallback: as hard as the fallback may brake, at its jerk.
[[nodiscard]] Longitudinal fallback_braking(const FrenetState& x0,
                                            const ReferenceTrajectoryParams& tp,
                                            double m_per_unit_s);

/// Longitudinal candidates, those within the axis limits, in this order: per cruise time a
/// levelling-off (after a hard acceleration) and quartics to the wanted speed and its
/// offsets; per leader and follow time a quintic to its RSS gap behind it; the braking
/// fallback, a gentle stop and the braking levels between.
[[nodiscard]] std::vector<LonCandidate> longitudinal_candidates(
    const TrajectoryRequest& req, const std::vector<const CarPrediction*>& leaders,
    const AlongRoadScale& scale, const Grid& g, const ReferenceParams& params,
    const core::CarFootprint& car, SpareBuffers& spare);

/// Soft costs of one longitudinal candidate in one lane: inside the RSS gap of the cars ahead,
/// and leaving too little room to cars closing from behind; over the whole horizon and over
/// its first change_early_window_s.
struct LaneCost {
  double full = 0.0;
  double early = 0.0;
};

/// The soft lane costs of every longitudinal candidate in every lane in play.
struct SoftLaneCosts {
  std::size_t lane_count = 0;
  std::vector<LaneCost> costs;  // index lon * lane_count + lane
  [[nodiscard]] const LaneCost& at(std::size_t lon, int lane) const {
    return costs[lon * lane_count + static_cast<std::size_t>(lane)];
  }
};

[[nodiscard]] SoftLaneCosts soft_lane_costs(const std::vector<LonCandidate>& lons,
                                            const std::vector<int>& lanes,
                                            const std::vector<LaneCars>& lane_cars, const Grid& g,
                                            double m_per_unit_s, const ReferenceParams& params,
                                            const core::CarFootprint& car);

}  // namespace overtake::planner::reference::trajectory_detail
