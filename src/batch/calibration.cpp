#include "overtake/batch/calibration.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <numeric>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/policies.hpp"
#include "overtake/batch/pool.hpp"
#include "overtake/core/units.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"

namespace overtake::batch {

using base::UsageError;
using run::Config;
using run::drive_on;
using run::DriveOptions;
using run::DriveResult;
using run::load_config;
using run::load_track;
using run::Track;
using run::validate_drive_options;
namespace {

using nlohmann::json;

/// A car that moves farther than this between two frames was placed again.
constexpr double kJumpM = 30.0;
/// A car's lane counts as changed once its d is within this of the new lane's centre.
constexpr double kSettleM = 1.0;
/// Rows this close in time to one of the car's lane changes are not lane keeping.
constexpr double kChangeMarginS = 3.0;
/// A placed car's first frame shows its cap read as m/s: above this, it is that frame.
constexpr double kFirstFrameMps = 30.0;
/// Pairs for "a car's speed 8-39 s later": these delays.
constexpr double kHoldDelaysS[] = {8.0, 16.0, 24.0, 32.0, 39.0};
constexpr double kHoldSmallMph = 0.5;
constexpr double kNearM = 60.0;
/// A car this far beyond the road's edges is parked off it.
constexpr double kOffRoadMarginM = 2.0;

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, i == 0 ? 0 : i - 1)];
}

double mean(const std::vector<double>& v) {
  if (v.empty()) return 0.0;
  return std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

}  // namespace

TrafficObserver::TrafficObserver(double loop_length_m, const core::RoadParams& road,
                                 double sample_every_s)
    : road_(road), sample_every_s_(sample_every_s), loop_length_m_(loop_length_m) {}

bool TrafficObserver::on_road(double d_m) const {
  return d_m > -kOffRoadMarginM && d_m < core::road_width_m(road_) + kOffRoadMarginM;
}

void TrafficObserver::begin_run() {
  ++run_;
  next_sample_s_ = 0.0;
  first_of_run_ = true;
  tracks_.clear();
}

void TrafficObserver::end_run(double distance_m, double duration_s) {
  ego_distance_m_ += distance_m;
  ego_duration_s_ += duration_s;
}

void TrafficObserver::observe(double t_s, const core::Telemetry& tel) {
  if (run_ < 0) begin_run();
  if (first_of_run_) {
    int parked = 0;
    for (const core::CarObservation& c : tel.cars) parked += on_road(c.d_m) ? 0 : 1;
    parked_at_start_.push_back(parked);
    first_of_run_ = false;
  }
  const bool sample = t_s + 1e-9 >= next_sample_s_;
  if (sample) next_sample_s_ = (std::floor(t_s / sample_every_s_ + 1e-9) + 1.0) * sample_every_s_;

  int near = 0;
  for (const core::CarObservation& c : tel.cars) {
    if (c.id < 0) continue;
    const auto id = static_cast<std::size_t>(c.id);
    if (tracks_.size() <= id) tracks_.resize(id + 1);
    CarTrack& tr = tracks_[id];
    const bool road = on_road(c.d_m);
    const double speed_mps = core::norm(c.velocity_mps);
    // Placement: onto the road, or a jump along it.
    const bool placed =
        road && (!tr.seen || !tr.on_road || core::distance(tr.position, c.position) > kJumpM);
    if (placed && tr.seen) {
      ++placements_;
      ++tr.segment;
      if (speed_mps > kFirstFrameMps) first_frame_mps_.push_back(speed_mps);
    }
    if (road && (placed || !tr.seen)) tr.settled_d_m = c.d_m;
    // Lane changes: the lane of d, once settled near its centre.
    if (road && !placed) {
      const int lane = core::lane_of(c.d_m, road_);
      const int settled = core::lane_of(tr.settled_d_m, road_);
      if (std::abs(c.d_m - core::lane_center_d(lane, road_)) < kSettleM) {
        if (lane != settled) changes_.push_back({run_, c.id, t_s});
        tr.settled_d_m = c.d_m;
      }
    }
    tr.seen = true;
    tr.on_road = road;
    tr.position = c.position;
    tr.t_s = t_s;
    if (!road) continue;

    double ds = std::fmod(c.s_m - tel.ego.s_m, loop_length_m_);
    if (ds > 0.5 * loop_length_m_) ds -= loop_length_m_;
    if (ds < -0.5 * loop_length_m_) ds += loop_length_m_;
    if (std::abs(ds) <= kNearM) ++near;
    if (!sample) continue;
    farthest_m_ = std::max(farthest_m_, std::abs(ds));
    const double mph = core::mps_to_mph(speed_mps);
    rows_.push_back({run_, c.id, tr.segment, t_s, mph, c.d_m, core::lane_of(c.d_m, road_)});
    (ds >= 0.0 ? ahead_speeds_ : behind_speeds_).push_back(mph);
  }
  if (sample) within_.push_back(near);
}

void TrafficObserver::speed_figures(TrafficFigures& f) const {
  std::vector<double> speeds;
  speeds.reserve(rows_.size());
  for (const Row& r : rows_) speeds.push_back(r.speed_mph);
  f.speed_mean_mph = mean(speeds);
  double var = 0.0;
  for (double v : speeds) var += (v - f.speed_mean_mph) * (v - f.speed_mean_mph);
  f.speed_sd_mph =
      speeds.size() > 1 ? std::sqrt(var / static_cast<double>(speeds.size() - 1)) : 0.0;
  f.speed_p5_mph = percentile(speeds, 0.05);
  f.speed_p50_mph = percentile(speeds, 0.50);
  f.speed_p95_mph = percentile(speeds, 0.95);
  f.share_above_50_mph =
      speeds.empty() ? 0.0
                     : static_cast<double>(std::count_if(speeds.begin(), speeds.end(),
                                                         [](double v) { return v > 50.0; })) /
                           static_cast<double>(speeds.size());
  f.ahead_mean_mph = mean(ahead_speeds_);
  f.behind_mean_mph = mean(behind_speeds_);
  std::vector<std::vector<double>> per_lane(static_cast<std::size_t>(road_.lane_count));
  for (const Row& r : rows_) per_lane[static_cast<std::size_t>(r.lane)].push_back(r.speed_mph);
  for (const auto& l : per_lane) f.lane_mean_mph.push_back(mean(l));
}

// How much a car's speed changes over the hold delays (the same car, the same placement).
void TrafficObserver::hold_figures(TrafficFigures& f) const {
  // Rows by car and time, for pairs and for the distance to lane changes.
  std::vector<std::size_t> order(rows_.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const Row& x = rows_[a];
    const Row& y = rows_[b];
    if (x.run != y.run) return x.run < y.run;
    if (x.car != y.car) return x.car < y.car;
    return x.t_s < y.t_s;
  });
  std::vector<double> changes;
  std::size_t j = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const Row& r = rows_[order[k]];
    for (const double delay : kHoldDelaysS) {
      j = k;
      while (j < order.size() && rows_[order[j]].run == r.run && rows_[order[j]].car == r.car &&
             rows_[order[j]].t_s < r.t_s + delay - 1e-9) {
        ++j;
      }
      if (j >= order.size()) break;
      const Row& later = rows_[order[j]];
      if (later.run != r.run || later.car != r.car || later.segment != r.segment) break;
      if (later.t_s - r.t_s > delay + sample_every_s_) break;
      changes.push_back(std::abs(later.speed_mph - r.speed_mph));
    }
  }
  f.hold_median_change_mph = percentile(changes, 0.5);
  f.hold_share_small =
      changes.empty()
          ? 0.0
          : static_cast<double>(std::count_if(changes.begin(), changes.end(),
                                              [](double v) { return v < kHoldSmallMph; })) /
                static_cast<double>(changes.size());
}

// Lane changes per car-minute, and how far cars wander from their lane's centre away from
// their lane changes.
void TrafficObserver::wander_figures(TrafficFigures& f) const {
  f.lane_changes_per_car_minute =
      f.car_minutes > 0.0 ? static_cast<double>(changes_.size()) / f.car_minutes : 0.0;
  std::vector<LaneChange> sorted_changes = changes_;
  const auto by_car_time = [](const LaneChange& a, const LaneChange& b) {
    if (a.run != b.run) return a.run < b.run;
    if (a.car != b.car) return a.car < b.car;
    return a.t_s < b.t_s;
  };
  std::sort(sorted_changes.begin(), sorted_changes.end(), by_car_time);
  std::vector<double> wander;
  for (const Row& r : rows_) {
    // The first lane change of this car at or after r.t_s - margin.
    const LaneChange key{r.run, r.car, r.t_s - kChangeMarginS};
    const auto it =
        std::lower_bound(sorted_changes.begin(), sorted_changes.end(), key, by_car_time);
    const bool near_change = it != sorted_changes.end() && it->run == r.run && it->car == r.car &&
                             it->t_s < r.t_s + kChangeMarginS;
    if (!near_change) wander.push_back(std::abs(r.d_m - core::lane_center_d(r.lane, road_)));
  }
  f.wander_p50_m = percentile(wander, 0.5);
  f.wander_p95_m = percentile(wander, 0.95);
  f.wander_max_m = wander.empty() ? 0.0 : *std::max_element(wander.begin(), wander.end());
}

TrafficFigures TrafficObserver::figures() const {
  TrafficFigures f;
  f.rows = static_cast<long>(rows_.size());
  f.car_minutes = static_cast<double>(rows_.size()) * sample_every_s_ / 60.0;
  speed_figures(f);
  hold_figures(f);
  wander_figures(f);
  if (!within_.empty()) {
    f.within_60m_mean =
        std::accumulate(within_.begin(), within_.end(), 0.0) / static_cast<double>(within_.size());
    f.within_60m_min = *std::min_element(within_.begin(), within_.end());
    f.within_60m_max = *std::max_element(within_.begin(), within_.end());
  }
  f.farthest_m = farthest_m_;
  f.placements = placements_;
  f.first_frames_seen = static_cast<int>(first_frame_mps_.size());
  if (!first_frame_mps_.empty()) {
    f.first_frame_min_mps = *std::min_element(first_frame_mps_.begin(), first_frame_mps_.end());
    f.first_frame_max_mps = *std::max_element(first_frame_mps_.begin(), first_frame_mps_.end());
  }
  if (!parked_at_start_.empty()) {
    f.parked_at_start = std::accumulate(parked_at_start_.begin(), parked_at_start_.end(), 0.0) /
                        static_cast<double>(parked_at_start_.size());
  }
  f.ego_mean_speed_mph =
      ego_duration_s_ > 0.0 ? core::mps_to_mph(ego_distance_m_ / ego_duration_s_) : 0.0;
  return f;
}

void TrafficObserver::merge(const TrafficObserver& o) {
  const int offset = run_ + 1;
  for (Row r : o.rows_) {
    r.run += offset;
    rows_.push_back(r);
  }
  for (LaneChange c : o.changes_) {
    c.run += offset;
    changes_.push_back(c);
  }
  run_ += o.run_ + 1;
  ahead_speeds_.insert(ahead_speeds_.end(), o.ahead_speeds_.begin(), o.ahead_speeds_.end());
  behind_speeds_.insert(behind_speeds_.end(), o.behind_speeds_.begin(), o.behind_speeds_.end());
  within_.insert(within_.end(), o.within_.begin(), o.within_.end());
  farthest_m_ = std::max(farthest_m_, o.farthest_m_);
  placements_ += o.placements_;
  first_frame_mps_.insert(first_frame_mps_.end(), o.first_frame_mps_.begin(),
                          o.first_frame_mps_.end());
  parked_at_start_.insert(parked_at_start_.end(), o.parked_at_start_.begin(),
                          o.parked_at_start_.end());
  ego_distance_m_ += o.ego_distance_m_;
  ego_duration_s_ += o.ego_duration_s_;
}

namespace {

// Drives one seed, its telemetry into `obs`; false when it was interrupted. Throws "seed N:
// why" when the run could not be driven or ended early otherwise.
bool observe_seed(const Track& track, const Config& config, DriveOptions o, std::uint64_t seed,
                  TrafficObserver& obs, const std::atomic<bool>* halt) {
  o.seed = seed;
  o.telemetry_tap = [&obs](double t, const core::Telemetry& tel) { obs.observe(t, tel); };
  try {
    obs.begin_run();
    const DriveResult r = drive_on(track, config, o, {}, halt);
    if (r.report.outcome.end == sim::RunEnd::stopped) return false;
    obs.end_run(r.report.distance_m, r.report.duration_s);
    if (r.report.outcome.ended_early())
      throw std::runtime_error(sim::ended_early_text(r.report.outcome));
  } catch (const std::exception& e) {
    throw std::runtime_error("seed " + std::to_string(seed) + ": " + e.what());
  }
  return true;
}

}  // namespace

Calibration calibrate(const CalibrateOptions& opts, const std::atomic<bool>* stop,
                      const std::function<void(const CalibrationProgress&)>& progress) {
  if (opts.seeds.empty()) throw UsageError("--seeds: no seed given");
  check_jobs(opts.jobs);
  check_policy_names({opts.policy}, nullptr);
  const Config config = load_config(opts.config);
  const std::shared_ptr<const Track> track = load_track(opts.map);
  DriveOptions base;
  base.minutes = opts.minutes;
  base.policy = opts.policy;
  base.traffic = opts.traffic;
  validate_drive_options(base);

  std::vector<TrafficObserver> observers(opts.seeds.size(),
                                         TrafficObserver(track->map.loop_length_m, config.road));
  std::vector<bool> finished(opts.seeds.size(), false);
  CalibrationProgress prog{0, opts.seeds.size(), 0.0};
  const auto wall0 = std::chrono::steady_clock::now();
  PoolOptions pool{opts.jobs, stop, PoolOrder::as_finished, {}};
  pool.tick = [&] {
    prog.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    if (progress) progress(prog);
  };
  try {
    (void)run_pool<bool>(
        opts.seeds.size(), pool,
        [&](std::size_t k, const std::atomic<bool>* halt) {
          return observe_seed(*track, config, base, opts.seeds[k], observers[k], halt);
        },
        [&](std::size_t k, bool&& done) {
          finished[k] = done;
          prog.done += done ? 1 : 0;
          if (progress) progress(prog);
          return true;
        });
  } catch (const std::exception& e) {
    throw std::runtime_error("calibration run failed: " + std::string(e.what()));
  }
  // The seeds that finished, in seed order: the same figures whatever the jobs.
  Calibration c;
  TrafficObserver all(track->map.loop_length_m, config.road);
  for (std::size_t k = 0; k < observers.size(); ++k) {
    if (finished[k]) all.merge(observers[k]);
  }
  c.figures = all.figures();
  c.runs = prog.done;
  c.interrupted = c.runs < opts.seeds.size();
  return c;
}

std::vector<CalibrationRow> compare_with_original(const TrafficFigures& f) {
  std::vector<CalibrationRow> rows;
  const auto add = [&rows](std::string key, std::string stat, std::string original,
                           std::string accept, double value, std::string shown,
                           std::optional<bool> pass) {
    rows.push_back({std::move(key), std::move(stat), std::move(original), std::move(accept), value,
                    std::move(shown), pass});
  };
  add("speed_mean_mph", "traffic speed, mean (sd) (mph)", "39.2 (5.7)", "36 - 42.5",
      f.speed_mean_mph, fmt("%.1f", f.speed_mean_mph) + fmt(" (%.1f)", f.speed_sd_mph),
      f.speed_mean_mph >= 36.0 && f.speed_mean_mph <= 42.5);
  add("speed_p95_mph", "traffic speed p5 / p50 / p95 (mph)", "31.8 / 39.1 / 47.2", "p95 <= 50",
      f.speed_p95_mph,
      fmt("%.1f", f.speed_p5_mph) + fmt(" / %.1f", f.speed_p50_mph) +
          fmt(" / %.1f", f.speed_p95_mph),
      f.speed_p95_mph <= 50.0);
  add("share_above_50_mph", "share of traffic rows above 50 mph", "0.4%", "<= 2%",
      f.share_above_50_mph, fmt("%.2f%%", 100.0 * f.share_above_50_mph),
      f.share_above_50_mph <= 0.02);
  add("ahead_behind_mean_mph", "cars ahead of the ego / behind, mean speed (mph)", "38.8 / 39.5",
      "", f.ahead_mean_mph, fmt("%.1f", f.ahead_mean_mph) + fmt(" / %.1f", f.behind_mean_mph),
      std::nullopt);
  std::string lanes;
  for (std::size_t l = 0; l < f.lane_mean_mph.size(); ++l) {
    lanes += (l ? " / " : "") + fmt("%.1f", f.lane_mean_mph[l]);
  }
  add("lane_mean_mph", "lane 0 / 1 / 2 mean speed (mph)", "38.2 / 38.7 / 41.5", "",
      f.lane_mean_mph.empty() ? 0.0 : f.lane_mean_mph.front(), lanes, std::nullopt);
  add("hold_median_change_mph", "a car's speed 8-39 s later: median change (mph)",
      "0.0 (64% < 0.5 mph)", "median <= 1", f.hold_median_change_mph,
      fmt("%.2f", f.hold_median_change_mph) +
          fmt(" (%.0f%% < 0.5 mph)", 100.0 * f.hold_share_small),
      f.hold_median_change_mph <= 1.0);
  add("lane_changes_per_car_minute", "traffic lane changes per car-minute",
      ">= 0.30 (a lower bound)", "0.15 - 1.0", f.lane_changes_per_car_minute,
      fmt("%.2f", f.lane_changes_per_car_minute),
      f.lane_changes_per_car_minute >= 0.15 && f.lane_changes_per_car_minute <= 1.0);
  add("within_60m_mean", "cars within +-60 m of the ego, mean per frame (range)", "4.0 (1-8)",
      "2.5 - 6", f.within_60m_mean,
      fmt("%.1f", f.within_60m_mean) + " (" + std::to_string(f.within_60m_min) + "-" +
          std::to_string(f.within_60m_max) + ")",
      f.within_60m_mean >= 2.5 && f.within_60m_mean <= 6.0);
  add("farthest_m", "all cars on the road within (m of the ego)", "+-201", "", f.farthest_m,
      fmt("+-%.0f", f.farthest_m), std::nullopt);
  add("wander_p50_m", "lateral wander |d - lane centre|, p50 / p95 / max (m)", "0.11 / 0.51 / 0.93",
      "p50 0.03 - 0.3", f.wander_p50_m,
      fmt("%.2f", f.wander_p50_m) + fmt(" / %.2f", f.wander_p95_m) + fmt(" / %.2f", f.wander_max_m),
      f.wander_p50_m >= 0.03 && f.wander_p50_m <= 0.3);
  add("first_frame_mps", "first frame of a newly placed car (m/s)",
      "40-53 (the cap read as m/s), then cap/2.237", "40 - 60", f.first_frame_max_mps,
      f.first_frames_seen == 0
          ? std::string("not seen")
          : fmt("%.1f", f.first_frame_min_mps) + fmt("-%.1f", f.first_frame_max_mps) + " (" +
                std::to_string(f.first_frames_seen) + " of " + std::to_string(f.placements) +
                " placements seen)",
      f.first_frames_seen > 0 && f.first_frame_min_mps >= 40.0 - 1e-6 &&
          f.first_frame_max_mps <= 60.0 + 1e-6);
  add("parked_at_start", "cars parked off the road at the start of a run", "10-12 of 12", "10 - 12",
      f.parked_at_start, fmt("%.1f", f.parked_at_start),
      f.parked_at_start >= 10.0 && f.parked_at_start <= 12.0);
  add("ego_mean_speed_mph", "the planner's own mean speed (mph)", "students: 38.7 - 46.2", "",
      f.ego_mean_speed_mph, fmt("%.1f", f.ego_mean_speed_mph), std::nullopt);
  return rows;
}

std::string format_calibration(const std::vector<CalibrationRow>& rows) {
  std::size_t w = 0;
  std::size_t wo = 0;
  std::size_t wv = 0;
  for (const CalibrationRow& r : rows) {
    w = std::max(w, r.statistic.size());
    wo = std::max(wo, r.original.size());
    wv = std::max(wv, r.shown.size());
  }
  std::string out;
  char buf[1024];
  std::snprintf(buf, sizeof buf, "  %-*s  %-*s  %-*s  %s\n", static_cast<int>(w), "statistic",
                static_cast<int>(wo), "original", static_cast<int>(wv), "overtake", "accept");
  out += buf;
  for (const CalibrationRow& r : rows) {
    const std::string verdict = !r.pass ? "" : (*r.pass ? "  pass" : "  FAIL");
    std::snprintf(buf, sizeof buf, "  %-*s  %-*s  %-*s  %s%s\n", static_cast<int>(w),
                  r.statistic.c_str(), static_cast<int>(wo), r.original.c_str(),
                  static_cast<int>(wv), r.shown.c_str(), r.accept.c_str(), verdict.c_str());
    out += buf;
  }
  return out;
}

json calibration_to_json(const TrafficFigures& f, const std::vector<CalibrationRow>& rows) {
  json j = json::object();
  json fig = {{"rows", f.rows},
              {"car_minutes", f.car_minutes},
              {"speed_mean_mph", f.speed_mean_mph},
              {"speed_sd_mph", f.speed_sd_mph},
              {"speed_p5_mph", f.speed_p5_mph},
              {"speed_p50_mph", f.speed_p50_mph},
              {"speed_p95_mph", f.speed_p95_mph},
              {"share_above_50_mph", f.share_above_50_mph},
              {"ahead_mean_mph", f.ahead_mean_mph},
              {"behind_mean_mph", f.behind_mean_mph},
              {"lane_mean_mph", f.lane_mean_mph},
              {"hold_median_change_mph", f.hold_median_change_mph},
              {"hold_share_small", f.hold_share_small},
              {"lane_changes_per_car_minute", f.lane_changes_per_car_minute},
              {"within_60m_mean", f.within_60m_mean},
              {"within_60m_min", f.within_60m_min},
              {"within_60m_max", f.within_60m_max},
              {"farthest_m", f.farthest_m},
              {"wander_p50_m", f.wander_p50_m},
              {"wander_p95_m", f.wander_p95_m},
              {"wander_max_m", f.wander_max_m},
              {"placements", f.placements},
              {"first_frames_seen", f.first_frames_seen},
              {"first_frame_min_mps", f.first_frame_min_mps},
              {"first_frame_max_mps", f.first_frame_max_mps},
              {"parked_at_start", f.parked_at_start},
              {"ego_mean_speed_mph", f.ego_mean_speed_mph}};
  j["figures"] = fig;
  json cmp = json::array();
  bool all = true;
  for (const CalibrationRow& r : rows) {
    json row = {{"key", r.key},
                {"statistic", r.statistic},
                {"original", r.original},
                {"accept", r.accept},
                {"overtake", r.shown}};
    row["pass"] = r.pass ? json(*r.pass) : json(nullptr);
    if (r.pass && !*r.pass) all = false;
    cmp.push_back(row);
  }
  j["comparison"] = cmp;
  j["all_pass"] = all;
  return j;
}

int report_calibration(const CalibrateOptions& o, const Calibration& c,
                       const std::filesystem::path& json) {
  const TrafficFigures& f = c.figures;
  const std::vector<CalibrationRow> rows = compare_with_original(f);
  std::printf(
      "overtake calibrate: %zu seeds x %g min, policy %s, %s traffic, %ld rows (%.0f "
      "car-minutes)\n",
      c.runs, o.minutes, o.policy.c_str(), o.traffic.c_str(), f.rows, f.car_minutes);
  std::cout << format_calibration(rows);
  std::cout.flush();
  nlohmann::json j = calibration_to_json(f, rows);
  if (c.interrupted) {
    j["interrupted"] = true;
    j["seeds_finished"] = c.runs;
  }
  if (!json.empty()) base::write_file_atomic(json, base::json_text(j, 2) + "\n");
  if (c.interrupted) {
    std::cerr << "calibrate: interrupted; the figures are those of the " << c.runs << " of "
              << o.seeds.size() << " seeds that finished\n";
    return base::kExitInterrupted;
  }
  return j["all_pass"].get<bool>() ? base::kExitOk : base::kExitFailure;
}

}  // namespace overtake::batch
