// keep_lane: an example overtake planner plugin (see overtake/planner_plugin.h).
//
// It keeps to its lane at just under the speed limit, follows the car ahead at a time gap,
// and moves one lane over when it is held up and the neighbouring lane is clear ahead and
// behind (and gives the change up, while still in its lane, when a car moves in beside it).
// Each cycle it keeps the start of its previous path (so the car's motion continues
// smoothly) and extends it along a cubic spline through the kept path's end and three
// anchors on the target lane, spacing the new points so that the speed changes with bounded
// acceleration and jerk.
//
// It reads only what version 2.0 of the header has, so that the tests can also build it
// against the frozen 2.0 header (tests/plugin/abi/v2_0) as a plugin nobody rebuilt.
//
// Build (needs only the installed header):
//   g++ -std=c++17 -O2 -shared -fPIC -I<prefix>/include keep_lane.cpp -o libkeep_lane.so

#include <overtake/planner_plugin.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <vector>

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMphPerMps = 2.23693629;

// Tuning, SI units.
constexpr double kCruiseMps = 49.0 / kMphPerMps;     // just under the 50 mph limit
constexpr double kMaxAccelMps2 = 4.0;                // tangential, either way
constexpr double kMaxJerkMps3 = 6.0;                 // change of that acceleration
constexpr double kSpeedGainPerS = 1.5;               // acceleration per m/s of speed error
constexpr double kPathDurationS = 1.0;               // the path ahead the planner answers
constexpr double kKeptS = 0.4;                       // of it, kept from the previous cycle
constexpr double kHeadwayS = 1.4;                    // time gap to the car ahead
constexpr double kStandstillGapM = 8.0;              // + this
constexpr double kGapGainPerS = 0.3;                 // m/s of closing speed per m of gap error
constexpr double kAnchorsM[] = {50.0, 85.0, 120.0};  // spline anchors ahead of the path's end
constexpr double kHeldUpMps = 2.0;                   // slower than cruise by this: look around
constexpr double kClearAheadM = 30.0;                // a lane change wants this much room ahead
constexpr double kClearBehindM = 15.0;               // ... and behind, plus closing speed x:
constexpr double kClosingLookS = 4.0;
constexpr double kChangeDurationS = 3.0;  // checked over the manoeuvre's length
constexpr int kChangeCooldownCycles = 60;
constexpr double kMergeConflictM = 20.0;  // a car this near in the lane beyond ...
constexpr double kMovingOverMps = 0.1;    // ... moving towards it faster than this
constexpr double kAbortBesideM = 10.0;    // a car this near beside in the target lane: abort
constexpr double kAbortUntilM = 1.8;      // ... while this near the lane it started from
// Closer than the standstill gap + this x speed: brake harder than comfort allows.
constexpr double kEmergencyHeadwayS = 0.5;
constexpr double kEmergencyAccelMps2 = 7.0;
constexpr double kEmergencyJerkMps3 = 15.0;

double lane_center(int lane, double width) {
  return width * (lane + 0.5);
}

// A natural cubic spline y(x) through knots with strictly increasing x.
class Spline {
 public:
  bool fit(const std::vector<double>& x, const std::vector<double>& y) {
    const std::size_t n = x.size();
    if (n < 2 || y.size() != n) return false;
    for (std::size_t i = 1; i < n; ++i) {
      if (!(x[i] > x[i - 1])) return false;
    }
    x_ = x;
    y_ = y;
    m_.assign(n, 0.0);  // second derivatives; natural: 0 at both ends
    std::vector<double> c(n, 0.0), r(n, 0.0);
    for (std::size_t i = 1; i + 1 < n; ++i) {  // Thomas algorithm on the interior rows
      const double h0 = x[i] - x[i - 1];
      const double h1 = x[i + 1] - x[i];
      const double a = h0 / 6.0;
      const double b = (h0 + h1) / 3.0 - a * c[i - 1];
      c[i] = (h1 / 6.0) / b;
      r[i] = ((y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0 - a * r[i - 1]) / b;
    }
    for (std::size_t i = n - 1; i-- > 1;) m_[i] = r[i] - c[i] * m_[i + 1];
    return true;
  }
  double operator()(double x) const { return eval(x, false); }
  double slope(double x) const { return eval(x, true); }

 private:
  double eval(double x, bool derivative) const {
    const std::size_t n = x_.size();
    std::size_t i = std::upper_bound(x_.begin(), x_.end(), x) - x_.begin();
    i = std::min(std::max<std::size_t>(i, 1), n - 1) - 1;  // segment [i, i+1]
    const double h = x_[i + 1] - x_[i];
    const double a = (x_[i + 1] - x) / h;
    const double b = (x - x_[i]) / h;
    if (derivative) {
      return (y_[i + 1] - y_[i]) / h +
             ((1.0 - 3.0 * a * a) * m_[i] + (3.0 * b * b - 1.0) * m_[i + 1]) * h / 6.0;
    }
    return a * y_[i] + b * y_[i + 1] +
           ((a * a * a - a) * m_[i] + (b * b * b - b) * m_[i + 1]) * h * h / 6.0;
  }
  std::vector<double> x_, y_, m_;
};

// The road: x, y and the normal as smooth functions of s (splines through the waypoints,
// a few of them repeated across the loop's seam).
class Road {
 public:
  bool build(const overtake_plugin_setup& setup) {
    const std::size_t n = setup.waypoint_count;
    if (n < 4 || !(setup.max_s > 0.0)) return false;
    max_s_ = setup.max_s;
    s0_ = setup.waypoints[0].s;
    std::vector<double> s, x, y, dx, dy;
    constexpr std::size_t kWrap = 3;
    for (std::size_t k = 0; k < n + 2 * kWrap; ++k) {
      const std::size_t i = (k + n - kWrap) % n;
      const overtake_waypoint& w = setup.waypoints[i];
      double offset = 0.0;
      if (k < kWrap) offset = -max_s_;
      if (k >= n + kWrap) offset = max_s_;
      s.push_back(w.s + offset);
      x.push_back(w.x);
      y.push_back(w.y);
      dx.push_back(w.dx);
      dy.push_back(w.dy);
    }
    return x_.fit(s, x) && y_.fit(s, y) && dx_.fit(s, dx) && dy_.fit(s, dy);
  }
  // Map position of the Frenet point (s, d).
  void xy(double s, double d, double& out_x, double& out_y) const {
    s = wrap(s);
    double nx = dx_(s), ny = dy_(s);
    const double len = std::hypot(nx, ny);
    if (len > 0.0) {
      nx /= len;
      ny /= len;
    }
    out_x = x_(s) + d * nx;
    out_y = y_(s) + d * ny;
  }
  // The road's unit normal at s (towards increasing d).
  void normal(double s, double& nx, double& ny) const {
    s = wrap(s);
    nx = dx_(s);
    ny = dy_(s);
    const double len = std::hypot(nx, ny);
    if (len > 0.0) {
      nx /= len;
      ny /= len;
    }
  }
  // Signed distance along the road from `from` to `to`, the shorter way round.
  double ahead(double from, double to) const {
    double g = std::fmod(to - from, max_s_);
    if (g > 0.5 * max_s_) g -= max_s_;
    if (g <= -0.5 * max_s_) g += max_s_;
    return g;
  }

 private:
  double wrap(double s) const {
    double w = std::fmod(s - s0_, max_s_);
    if (w < 0.0) w += max_s_;
    return s0_ + w;
  }
  Spline x_, y_, dx_, dy_;
  double max_s_ = 0.0;
  double s0_ = 0.0;
};

struct Car {
  double s = 0.0;  // now
  double d = 0.0;
  double speed = 0.0;   // m/s
  double d_rate = 0.0;  // m/s, sideways (towards increasing d)
};

}  // namespace

struct overtake_plugin_handle {
  Road road;
  int lanes = 3;
  double lane_width = 4.0;
  double dt = 0.02;
  int lane = -1;       // the target lane; -1 until the first telemetry
  int from_lane = -1;  // during a lane change: the lane it started from
  int cooldown = 0;
  double accel = 0.0;
  double cruise_mps = kCruiseMps;  // the parameter "cruise_mps" (`overtake tune`) may change it
  // Speed and acceleration planned for each point of the last path sent.
  std::vector<double> sent_v, sent_a, kept_v, kept_a;

  // Does the car occupy `lane` (its body, allowing for a car halfway across)?
  bool in_lane(const Car& c, int l) const {
    return std::abs(c.d - lane_center(l, lane_width)) < 0.5 * lane_width + 0.6;
  }

  // Is `l` clear for a change begun at ego_s, the ego at speed v?
  bool clear(const std::vector<Car>& cars, int l, double ego_s, double v, double lead_gap) const {
    double nearest_ahead = 1e9;
    for (const Car& c : cars) {
      const double gap = road.ahead(ego_s, c.s);
      // A car in the lane beyond, near and moving over into `l`, takes it too.
      const double beyond = c.d - lane_center(l, lane_width);
      if (std::abs(beyond) > 0.5 * lane_width && std::abs(beyond) < 1.5 * lane_width &&
          std::abs(gap) < kMergeConflictM &&
          beyond * c.d_rate < -kMovingOverMps * std::abs(beyond)) {
        return false;
      }
      if (!in_lane(c, l)) continue;
      if (gap >= 0.0) nearest_ahead = std::min(nearest_ahead, gap);
      for (double t = 0.0; t <= kChangeDurationS; t += 0.5) {  // now and over the manoeuvre
        const double g = gap + (c.speed - v) * t;
        if (g > -kClearBehindM - std::max(0.0, c.speed - v) * kClosingLookS && g < kClearAheadM) {
          return false;
        }
      }
    }
    return nearest_ahead > lead_gap + 10.0;  // only worth it with more room than here
  }

  int plan(const overtake_telemetry& in, overtake_path& out) {
    const std::size_t prev_n = in.previous_path_count;
    if (lane < 0) {
      lane = std::clamp(static_cast<int>(std::floor(in.d / lane_width)), 0, lanes - 1);
    }
    if (cooldown > 0) --cooldown;

    std::vector<Car> cars;
    cars.reserve(in.sensor_fusion_count);
    for (std::size_t i = 0; i < in.sensor_fusion_count; ++i) {
      const double* row = in.sensor_fusion[i];
      double nx = 0.0, ny = 0.0;
      road.normal(row[OVERTAKE_SF_S], nx, ny);
      cars.push_back({row[OVERTAKE_SF_S], row[OVERTAKE_SF_D],
                      std::hypot(row[OVERTAKE_SF_VX], row[OVERTAKE_SF_VY]),
                      row[OVERTAKE_SF_VX] * nx + row[OVERTAKE_SF_VY] * ny});
    }

    // Keep the start of the previous path.
    const std::size_t want = static_cast<std::size_t>(std::lround(kPathDurationS / dt));
    std::size_t keep = std::min(prev_n, static_cast<std::size_t>(std::lround(kKeptS / dt)));
    keep = std::min(keep, out.capacity);
    double ref_x = in.x, ref_y = in.y, ref_yaw = in.yaw * kPi / 180.0;
    double v = in.speed / kMphPerMps;
    double back_x = ref_x - std::cos(ref_yaw), back_y = ref_y - std::sin(ref_yaw);
    double ref_s = in.s;
    double travelled = 0.0;
    {
      double lx = in.x, ly = in.y;
      for (std::size_t i = 0; i < keep; ++i) {
        travelled += std::hypot(in.previous_path_x[i] - lx, in.previous_path_y[i] - ly);
        lx = in.previous_path_x[i];
        ly = in.previous_path_y[i];
        out.next_x[i] = lx;
        out.next_y[i] = ly;
      }
    }
    if (keep >= 2) {
      ref_x = in.previous_path_x[keep - 1];
      ref_y = in.previous_path_y[keep - 1];
      back_x = in.previous_path_x[keep - 2];
      back_y = in.previous_path_y[keep - 2];
      ref_yaw = std::atan2(ref_y - back_y, ref_x - back_x);
      v = std::hypot(ref_x - back_x, ref_y - back_y) / dt;
      ref_s = keep == prev_n ? in.end_path_s : in.s + travelled;
    } else {
      keep = 0;
      accel = 0.0;
    }
    // Speed and acceleration at the kept end, as planned when it was sent.
    const std::size_t consumed = sent_v.size() >= prev_n ? sent_v.size() - prev_n : 0;
    if (keep >= 2 && consumed + keep <= sent_v.size()) {
      v = sent_v[consumed + keep - 1];
      accel = sent_a[consumed + keep - 1];
      kept_v.assign(sent_v.begin() + consumed, sent_v.begin() + consumed + keep);
      kept_a.assign(sent_a.begin() + consumed, sent_a.begin() + consumed + keep);
    } else {
      kept_v.assign(keep, v);
      kept_a.assign(keep, accel);
    }
    const double horizon_t = static_cast<double>(keep) * dt;

    // The car ahead: in the target lane; in a lane the ego is still leaving, only when close.
    double lead_gap = 1e9, lead_speed = cruise_mps;
    const double close_m = kStandstillGapM + kHeadwayS * v;
    for (const Car& car : cars) {
      const double gap = road.ahead(ref_s, car.s + car.speed * horizon_t);
      if (!(gap > 0.0 && gap < lead_gap)) continue;
      const bool target_lane = in_lane(car, lane);
      const bool beside = std::abs(car.d - in.d) < 0.5 * lane_width + 0.6;
      if (target_lane || (beside && gap < close_m)) {
        lead_gap = gap;
        lead_speed = car.speed;
      }
    }

    // A lane change when held up, settled in the lane and clear alongside.
    const bool settled = std::abs(in.d - lane_center(lane, lane_width)) < 0.4;
    if (settled && cooldown == 0 && lead_gap < 80.0 && lead_speed < cruise_mps - kHeldUpMps) {
      int best = -1;
      for (int l : {lane - 1, lane + 1}) {
        if (l < 0 || l >= lanes) continue;
        if (clear(cars, l, in.s, in.speed / kMphPerMps, lead_gap)) {
          best = l;
          break;
        }
      }
      if (best >= 0) {
        from_lane = lane;
        lane = best;
        cooldown = kChangeCooldownCycles;
      }
    } else if (!settled && from_lane >= 0 && from_lane != lane) {
      // Changing lanes, not yet across the line: back to where it came from when a car turns
      // up beside it in the target lane (from behind, or moving over from the far side).
      const bool across = std::abs(in.d - lane_center(from_lane, lane_width)) > kAbortUntilM;
      for (const Car& car : cars) {
        if (across) break;
        if (in_lane(car, lane) && !in_lane(car, from_lane) &&
            std::abs(road.ahead(in.s, car.s)) < kAbortBesideM) {
          lane = from_lane;
          from_lane = -1;
          cooldown = kChangeCooldownCycles;
          break;
        }
      }
    }

    // Speed wanted: cruise, or the leader's speed corrected for the gap.
    double target = cruise_mps;
    if (lead_gap < 1e8) {
      const double desired = kStandstillGapM + kHeadwayS * v;
      target = std::min(target, lead_speed + kGapGainPerS * (lead_gap - desired));
    }
    target = std::max(target, 0.0);

    // The spline in the frame of the kept end (x ahead, y to the left).
    const double c = std::cos(ref_yaw), s = std::sin(ref_yaw);
    const auto local = [&](double wx, double wy, double& lx, double& ly) {
      lx = (wx - ref_x) * c + (wy - ref_y) * s;
      ly = -(wx - ref_x) * s + (wy - ref_y) * c;
    };
    std::vector<double> kx, ky;
    double lx = 0.0, ly = 0.0;
    local(back_x, back_y, lx, ly);
    if (!(lx < -1e-3)) {  // standing still: a point behind along the heading
      lx = -1.0;
      ly = 0.0;
    }
    kx.push_back(lx);
    ky.push_back(ly);
    kx.push_back(0.0);
    ky.push_back(0.0);
    double d_target = lane_center(lane, lane_width);
    if (lane == lanes - 1) d_target -= 0.15;  // keep clear of the road's outer edge
    for (double a : kAnchorsM) {
      double wx = 0.0, wy = 0.0;
      road.xy(ref_s + a, d_target, wx, wy);
      local(wx, wy, lx, ly);
      if (!(lx > kx.back() + 1.0)) continue;
      kx.push_back(lx);
      ky.push_back(ly);
    }
    Spline path;
    if (kx.size() < 3 || !path.fit(kx, ky)) {
      out.error = "keep_lane: cannot fit a path (anchors behind the car)";
      return 1;
    }

    // New points: the speed follows the target with bounded acceleration and jerk.
    const bool emergency = lead_gap < kStandstillGapM + kEmergencyHeadwayS * v;
    const double brake = emergency ? kEmergencyAccelMps2 : kMaxAccelMps2;
    const double jerk = emergency ? kEmergencyJerkMps3 : kMaxJerkMps3;
    sent_v = kept_v;
    sent_a = kept_a;
    std::size_t n = keep;
    double x = 0.0;
    const std::size_t total = std::min(std::max(want, keep), out.capacity);
    while (n < total) {
      const double a_want = std::clamp(kSpeedGainPerS * (target - v), -brake, kMaxAccelMps2);
      accel = std::clamp(a_want, accel - jerk * dt, accel + jerk * dt);
      v = std::max(0.0, v + accel * dt);
      if (v == 0.0) accel = 0.0;
      const double step = v * dt;
      const double dydx = path.slope(x + 0.5 * step);
      x += step / std::sqrt(1.0 + dydx * dydx);
      const double y = path(x);
      out.next_x[n] = ref_x + x * c - y * s;
      out.next_y[n] = ref_y + x * s + y * c;
      sent_v.push_back(v);
      sent_a.push_back(accel);
      ++n;
    }
    out.count = n;
    return 0;
  }
};

namespace {
const overtake_plugin_info kInfo = {
    "keep_lane",
    "follows its lane at 49 mph with a time gap to the car ahead; overtakes when held up"};

// The number given for `name` in a flat JSON object of numbers ({"cruise_mps":21.5}), as
// overtake passes parameters; false when it is not there.
bool json_number(const char* json, const char* name, double& value) {
  if (json == nullptr) return false;
  char key[64];
  std::snprintf(key, sizeof key, "\"%s\"", name);
  const char* at = std::strstr(json, key);
  if (at == nullptr) return false;
  at = std::strchr(at + std::strlen(key), ':');
  if (at == nullptr) return false;
  char* end = nullptr;
  value = std::strtod(at + 1, &end);
  return end != at + 1;
}
}  // namespace

int overtake_plugin_abi_version(void) {
  return OVERTAKE_PLUGIN_ABI_VERSION;
}

const overtake_plugin_info* overtake_plugin_get_info(void) {
  return &kInfo;
}

overtake_plugin_handle* overtake_plugin_create(const overtake_plugin_setup* setup, char* error,
                                               size_t error_size) {
  auto* h = new (std::nothrow) overtake_plugin_handle;
  if (h == nullptr) {
    std::snprintf(error, error_size, "keep_lane: out of memory");
    return nullptr;
  }
  if (setup->lane_count < 1 || !(setup->lane_width > 0.0) || !(setup->step_time > 0.0) ||
      !h->road.build(*setup)) {
    // The reason with the numbers that made it so: the buffer is the caller's.
    std::snprintf(error, error_size,
                  "keep_lane: the map or the road is unusable (%zu waypoints, loop of %g m, "
                  "%d lanes of %g m, step %g s)",
                  setup->waypoint_count, setup->max_s, setup->lane_count, setup->lane_width,
                  setup->step_time);
    delete h;
    return nullptr;
  }
  h->lanes = setup->lane_count;
  h->lane_width = setup->lane_width;
  h->dt = setup->step_time;
  if (json_number(setup->config_json, "cruise_mps", h->cruise_mps) &&
      !(h->cruise_mps > 0.0 && h->cruise_mps <= kCruiseMps)) {
    std::snprintf(error, error_size, "keep_lane: cruise_mps must be in (0, %g] (got %g)",
                  kCruiseMps, h->cruise_mps);
    delete h;
    return nullptr;
  }
  return h;
}

int overtake_plugin_plan(overtake_plugin_handle* handle, const overtake_telemetry* in,
                         overtake_path* out) {
  try {  // nothing may leave a C function
    return handle->plan(*in, *out);
  } catch (const std::exception&) {
    out->error = "keep_lane: internal error";
    return 2;
  }
}

void overtake_plugin_destroy(overtake_plugin_handle* handle) {
  delete handle;
}
