#include "overtake/planner/seed_policies.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "overtake/core/units.hpp"
#include "overtake/planner/spline_path.hpp"

namespace overtake::planner {

// ---- shared ---------------------------------------------------------------------------

SeedPolicyBase::SeedPolicyBase(const core::ReferenceLine& line, const PlannerParams& params)
    : line_(line),
      road_(params.road),
      step_s_(params.step_s),
      base_(params.walkthrough),
      lane_(params.walkthrough.start_lane) {}

double SeedPolicyBase::planning_s(const core::Telemetry& t) {
  return t.previous_path.empty() ? t.ego.s_m : t.end_path.s_m;
}

std::vector<SeenCar> SeedPolicyBase::seen_cars(const core::Telemetry& t, bool project) const {
  const double from_s = planning_s(t);
  const double ahead_time_s = project ? static_cast<double>(t.previous_path.size()) * step_s_ : 0.0;
  std::vector<SeenCar> out;
  out.reserve(t.cars.size());
  for (const core::CarObservation& c : t.cars) {
    const double speed = core::norm(c.velocity_mps);
    out.push_back({line_.s_ahead(from_s, c.s_m + ahead_time_s * speed), speed, c.d_m});
  }
  return out;
}

bool SeedPolicyBase::in_lane(double d_m, int lane) const {
  const double centre = core::lane_center_d(lane, road_);
  const double half = 0.5 * road_.lane_width_m;
  return d_m < centre + half && d_m > centre - half;
}

bool SeedPolicyBase::too_close(const std::vector<SeenCar>& cars) const {
  return std::any_of(cars.begin(), cars.end(), [&](const SeenCar& c) {
    return in_lane(c.d_m, lane_) && c.gap_m > 0.0 && c.gap_m < base_.too_close_m;
  });
}

void SeedPolicyBase::speed_up(double step_mps) {
  if (ref_speed_mps_ < base_.target_speed_mps) ref_speed_mps_ += step_mps;
}

void SeedPolicyBase::slow_down(double step_mps) {
  // As in the walkthrough policy: the write-ups have no floor; one step keeps points apart.
  ref_speed_mps_ = std::max(ref_speed_mps_ - step_mps, base_.speed_step_mps);
}

std::vector<core::Vec2> SeedPolicyBase::path(const core::Telemetry& t,
                                             const std::vector<double>& anchors_m,
                                             int points) const {
  SplinePathSpec spec;
  spec.target_d_m = core::lane_center_d(lane_, road_);
  spec.ref_speed_mps = ref_speed_mps_;
  spec.anchor_distances_m = anchors_m;
  spec.path_points = points;
  spec.horizon_x_m = base_.horizon_x_m;
  spec.step_s = step_s_;
  return spline_path(t, line_, spec);
}

// ---- seed000 --------------------------------------------------------------------------

Seed000Policy::Seed000Policy(const core::ReferenceLine& line, const PlannerParams& params)
    : SeedPolicyBase(line, params), p_(params.seed000) {}

core::PlanResult Seed000Policy::plan(const core::Telemetry& t) {
  const auto cars = seen_cars(t, true);
  const auto n = static_cast<std::size_t>(lane_count());
  std::vector<double> gap_ahead(n, p_.no_car_gap_m), gap_behind(n, p_.no_car_gap_m),
      speed_ahead(n, 0.0);
  for (const SeenCar& c : cars) {
    const auto l = static_cast<std::size_t>(core::lane_of(c.d_m, road_));
    if (c.gap_m > 0.0) {
      if (gap_ahead[l] > c.gap_m) {
        gap_ahead[l] = c.gap_m;
        speed_ahead[l] = c.speed_mps;
      }
    } else if (gap_behind[l] > -c.gap_m) {
      gap_behind[l] = -c.gap_m;
    }
  }
  if (too_close(cars)) {
    slow_down(base_.speed_step_mps);
    const double speed_mph = core::mps_to_mph(t.ego.speed_mps);
    const double min_ahead = p_.min_gap_ahead_per_mph_m * speed_mph;
    const double min_behind = speed_mph > 0.0 ? p_.min_gap_behind_mph_m / speed_mph
                                              : std::numeric_limits<double>::infinity();
    auto roomy = [&](int l) {
      const auto i = static_cast<std::size_t>(l);
      return gap_behind[i] > min_behind && gap_ahead[i] > min_ahead;
    };
    auto empty = [&](int l) { return speed_ahead[static_cast<std::size_t>(l)] == 0.0; };
    auto faster = [&](int l) {
      return speed_ahead[static_cast<std::size_t>(l)] >
             speed_ahead[static_cast<std::size_t>(lane_)];
    };
    const int last = lane_count() - 1;
    if (lane_ == 0 || lane_ == last) {
      const int middle = lane_ == 0 ? 1 : last - 1;
      if (middle >= 0 && middle <= last && roomy(middle) && (faster(middle) || empty(middle)))
        lane_ = middle;
    } else {
      const int left = lane_ - 1;
      const int right = lane_ + 1;
      const auto gl = gap_ahead[static_cast<std::size_t>(left)];
      const auto gr = gap_ahead[static_cast<std::size_t>(right)];
      if (roomy(left) && empty(left)) {
        lane_ = left;
      } else if (roomy(right) && empty(right)) {
        lane_ = right;
      } else if (gl > gr && roomy(left)) {
        if (faster(left) || gl > p_.open_lane_gap_m) lane_ = left;
      } else if (gr > gl && roomy(right)) {
        if (faster(right) || gr > p_.open_lane_gap_m) lane_ = right;
      }
    }
  } else {
    speed_up(base_.speed_step_mps);
  }
  return core::normal_plan(path(t));
}

// ---- seed001 --------------------------------------------------------------------------

Seed001Policy::Seed001Policy(const core::ReferenceLine& line, const PlannerParams& params)
    : SeedPolicyBase(line, params), p_(params.seed001) {}

core::PlanResult Seed001Policy::plan(const core::Telemetry& t) {
  const auto cars = seen_cars(t, true);
  bool change_left = lane_ > 0;
  bool change_right = lane_ < lane_count() - 1;
  for (const SeenCar& c : cars) {
    const bool near =
        (c.gap_m > 0.0 && c.gap_m < p_.gap_front_m) || (c.gap_m < 0.0 && -c.gap_m < p_.gap_rear_m);
    if (!near) continue;
    if (change_left && in_lane(c.d_m, lane_ - 1)) change_left = false;
    if (change_right && in_lane(c.d_m, lane_ + 1)) change_right = false;
  }
  if (too_close(cars)) {
    slow_down(base_.speed_step_mps);
    ++too_longer_;
    if (change_left && too_longer_ > p_.patience_cycles) {
      too_longer_ = 0;
      --lane_;
    } else if (change_right && too_longer_ > p_.patience_cycles) {
      too_longer_ = 0;
      ++lane_;
    }
  } else {
    speed_up(base_.speed_step_mps);
  }
  return core::normal_plan(path(t));
}

// ---- seed002 --------------------------------------------------------------------------

Seed002Policy::Seed002Policy(const core::ReferenceLine& line, const PlannerParams& params)
    : SeedPolicyBase(line, params), p_(params.seed002) {}

core::PlanResult Seed002Policy::plan(const core::Telemetry& t) {
  const auto cars = seen_cars(t, true);
  std::vector<bool> proximity(static_cast<std::size_t>(lane_count()), false);
  for (const SeenCar& c : cars) {
    if ((c.gap_m >= 0.0 && c.gap_m < p_.proximity_ahead_m) ||
        (c.gap_m < 0.0 && -c.gap_m < p_.proximity_behind_m)) {
      proximity[static_cast<std::size_t>(core::lane_of(c.d_m, road_))] = true;
    }
  }
  if (too_close(cars)) {
    if (lane_ > 0 && !proximity[static_cast<std::size_t>(lane_ - 1)]) {
      --lane_;
    } else if (lane_ < lane_count() - 1 && !proximity[static_cast<std::size_t>(lane_ + 1)]) {
      ++lane_;
    } else {
      slow_down(base_.speed_step_mps);
    }
  } else {
    speed_up(base_.speed_step_mps);
  }
  return core::normal_plan(path(t, base_.anchor_distances_m, p_.path_points));
}

// ---- seed003 --------------------------------------------------------------------------

Seed003Policy::Seed003Policy(const core::ReferenceLine& line, const PlannerParams& params)
    : SeedPolicyBase(line, params), p_(params.seed003) {}

core::PlanResult Seed003Policy::plan(const core::Telemetry& t) {
  const auto cars = seen_cars(t, true);
  bool safe_left = true;
  bool safe_right = true;
  double min_speed_left = std::numeric_limits<double>::infinity();
  double min_speed_right = std::numeric_limits<double>::infinity();
  bool close = false;
  double nearest_gap = std::numeric_limits<double>::infinity();
  double target_speed = 0.0;
  for (const SeenCar& c : cars) {
    const int car_lane = core::lane_of(c.d_m, road_);
    const bool forward = c.gap_m > 0.0 && c.gap_m <= p_.max_dist_front_m;
    const bool back = c.gap_m <= 0.0 && -c.gap_m <= p_.max_dist_back_m;
    if (forward || back) {
      if (car_lane == lane_ - 1)
        safe_left = false;
      else if (car_lane == lane_ + 1)
        safe_right = false;
    }
    if (safe_left && safe_right) {
      if (car_lane == lane_ - 1)
        min_speed_left = std::min(min_speed_left, c.speed_mps);
      else if (car_lane == lane_ + 1)
        min_speed_right = std::min(min_speed_right, c.speed_mps);
    }
    if (in_lane(c.d_m, lane_) && c.gap_m > 0.0 && c.gap_m < base_.too_close_m) {
      close = true;
      if (c.gap_m < nearest_gap) {
        nearest_gap = c.gap_m;
        target_speed = c.speed_mps;
      }
    }
  }
  const int last = lane_count() - 1;
  const int middle = last / 2;
  const bool can_left = safe_left && lane_ > 0;
  const bool can_right = safe_right && lane_ < last;
  if (close && lane_ == middle && can_left && can_right) {
    lane_ += min_speed_left < min_speed_right ? 1 : -1;
    allow_strong_acc_ = true;
  } else if (close && can_left) {
    --lane_;
    allow_strong_acc_ = true;
  } else if (close && can_right) {
    ++lane_;
    allow_strong_acc_ = true;
  } else if (close && ref_speed_mps_ > target_speed) {
    ref_speed_mps_ = std::max(ref_speed_mps_ - base_.speed_step_mps, target_speed);
    ref_speed_mps_ = std::max(ref_speed_mps_, base_.speed_step_mps);
    allow_strong_acc_ = false;
  } else if (close) {
    ref_speed_mps_ = std::max(target_speed, base_.speed_step_mps);
    allow_strong_acc_ = false;
  } else if (lane_ != middle && ref_speed_mps_ >= p_.middle_return_speed_mps) {
    if (lane_ > middle && can_left) {
      --lane_;
      allow_strong_acc_ = true;
    } else if (lane_ < middle && can_right) {
      ++lane_;
      allow_strong_acc_ = true;
    }
  } else if (ref_speed_mps_ < base_.target_speed_mps) {
    ref_speed_mps_ += allow_strong_acc_ ? p_.strong_speed_step_mps : base_.speed_step_mps;
  }
  return core::normal_plan(path(t));
}

// ---- seed004 --------------------------------------------------------------------------

Seed004Policy::Seed004Policy(const core::ReferenceLine& line, const PlannerParams& params)
    : SeedPolicyBase(line, params), p_(params.seed004) {}

bool Seed004Policy::lane_free(const core::Telemetry& t, int lane, double my_s_m) const {
  const double my_speed_as_written = core::mps_to_mph(t.ego.speed_mps);  // mph, against m/s below
  for (const core::CarObservation& c : t.cars) {
    if (static_cast<int>(c.d_m) / static_cast<int>(road_.lane_width_m) != lane) continue;
    const double gap = line_.s_ahead(my_s_m, c.s_m);
    if ((gap >= 0.0 && gap <= p_.free_ahead_m) || (gap < 0.0 && -gap < p_.free_behind_m))
      return false;
    const double other_speed_mps = core::norm(c.velocity_mps);
    if (-gap > p_.free_behind_m && -gap < p_.faster_behind_m &&
        my_speed_as_written < other_speed_mps) {
      return false;
    }
  }
  return true;
}

core::PlanResult Seed004Policy::plan(const core::Telemetry& t) {
  const auto cars = seen_cars(t, true);
  bool close = false;
  for (const SeenCar& c : cars) {
    if (in_lane(c.d_m, lane_) && c.gap_m > 0.0 && c.gap_m < base_.too_close_m) {
      close = true;
      // ref_vel -= (ref_vel - check_speed) / 30 with ref_vel in mph and check_speed in m/s:
      // in SI, a pull toward the other car's speed read as if it were mph.
      const double other_read_as_mph = core::mph_to_mps(c.speed_mps);
      ref_speed_mps_ -= (ref_speed_mps_ - other_read_as_mph) / p_.speed_match_divisor;
      ref_speed_mps_ = std::max(ref_speed_mps_, base_.speed_step_mps);
    }
  }
  if (!close) {
    speed_up(base_.speed_step_mps);
  } else {
    const double my_s = planning_s(t);
    if (lane_ < lane_count() - 1 && lane_free(t, lane_ + 1, my_s)) {
      ++lane_;
    } else if (lane_ > 0 && lane_free(t, lane_ - 1, my_s)) {
      --lane_;
    }
  }
  std::vector<double> anchors = base_.anchor_distances_m;
  const int ego_lane = static_cast<int>(t.ego.d_m) / static_cast<int>(road_.lane_width_m);
  if (lane_ != ego_lane && !anchors.empty()) {
    anchors.front() = std::max(anchors.front(), p_.change_first_anchor_m);
  }
  return core::normal_plan(path(t, anchors, base_.path_points));
}

}  // namespace overtake::planner

namespace overtake::planner {

bool SeedPolicyBase::archive_state(core::StateArchive& ar) {
  ar.part("seed policy");
  ar.io_range(lane_, 0, road_.lane_count - 1, "lane");
  ar.io_speed(ref_speed_mps_, "reference speed");
  return true;
}

bool Seed001Policy::archive_state(core::StateArchive& ar) {
  SeedPolicyBase::archive_state(ar);
  ar.io(too_longer_, "cycles slowing");
  return true;
}

bool Seed003Policy::archive_state(core::StateArchive& ar) {
  SeedPolicyBase::archive_state(ar);
  ar.io(allow_strong_acc_, "strong acceleration");
  return true;
}

}  // namespace overtake::planner
