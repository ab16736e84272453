#pragma once
// Calibration: what a planner observes of the traffic, from the sensor fusion it receives,
// measured the way the figures recorded from the original simulator were measured, and
// compared with them (docs/fidelity.md).

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/core/road.hpp"
#include "overtake/core/telemetry.hpp"

namespace overtake::batch {

/// The traffic figures of one or more runs.
struct TrafficFigures {
  long rows = 0;             ///< sampled sensor-fusion rows of cars on the road
  double car_minutes = 0.0;  ///< time cars were observed on the road
  double speed_mean_mph = 0.0;
  double speed_sd_mph = 0.0;
  double speed_p5_mph = 0.0;
  double speed_p50_mph = 0.0;
  double speed_p95_mph = 0.0;
  double share_above_50_mph = 0.0;  ///< fraction of rows
  double ahead_mean_mph = 0.0;      ///< cars ahead of the ego
  double behind_mean_mph = 0.0;
  std::vector<double> lane_mean_mph;    ///< per lane
  double hold_median_change_mph = 0.0;  ///< |speed change| of a car 8-39 s later, median
  double hold_share_small = 0.0;        ///< ... share under 0.5 mph
  double lane_changes_per_car_minute = 0.0;
  double within_60m_mean = 0.0;  ///< cars within +-60 m of the ego (along s), per frame
  int within_60m_min = 0;
  int within_60m_max = 0;
  double farthest_m = 0.0;    ///< largest |s - ego s| of a car on the road
  double wander_p50_m = 0.0;  ///< |d - lane centre| away from lane changes
  double wander_p95_m = 0.0;
  double wander_max_m = 0.0;
  int placements = 0;                ///< cars seen newly placed
  double first_frame_min_mps = 0.0;  ///< speed of a placed car on the frame right after its
  double first_frame_max_mps = 0.0;  ///<   placement (when the planner saw that frame)
  int first_frames_seen = 0;
  double parked_at_start = 0.0;     ///< cars off the road in a run's first telemetry (mean)
  double ego_mean_speed_mph = 0.0;  ///< the planner's own mean speed
};

/// Accumulates the figures from the telemetry a planner receives, run by run.
class TrafficObserver {
 public:
  /// `loop_length_m`: the map's loop length (s wraps there); rows are sampled every
  /// `sample_every_s` of world time.
  explicit TrafficObserver(double loop_length_m, const core::RoadParams& road = {},
                           double sample_every_s = 0.5);
  /// Starts a new run (a new world: cars are tracked afresh).
  void begin_run();
  /// One telemetry message, received at world time t_s (non-decreasing within a run).
  void observe(double t_s, const core::Telemetry& telemetry);
  /// Ends the current run: its ego distance and duration count for the ego's mean speed.
  void end_run(double distance_m, double duration_s);
  [[nodiscard]] TrafficFigures figures() const;
  /// Adds another observer's runs (as runs of their own).
  void merge(const TrafficObserver& other);

 private:
  struct Row {
    int run = 0;
    int car = 0;
    int segment = 0;  // placement count of that car in that run
    double t_s = 0.0;
    double speed_mph = 0.0;
    double d_m = 0.0;
    int lane = 0;
  };
  struct CarTrack {
    bool seen = false;
    bool on_road = false;
    core::Vec2 position;
    double t_s = 0.0;
    int segment = 0;
    double settled_d_m = 0.0;
    bool first_pending = false;  // placed at the last frame: the next frame shows its speed
  };
  [[nodiscard]] bool on_road(double d_m) const;
  // The parts of figures(): speeds (all, ahead, behind, per lane), holds, wander.
  void speed_figures(TrafficFigures& f) const;
  void hold_figures(TrafficFigures& f) const;
  void wander_figures(TrafficFigures& f) const;

  core::RoadParams road_;
  double sample_every_s_;
  int run_ = -1;
  double next_sample_s_ = 0.0;
  bool first_of_run_ = true;
  std::vector<CarTrack> tracks_;
  std::vector<Row> rows_;
  struct LaneChange {
    int run = 0;
    int car = 0;
    double t_s = 0.0;
  };
  std::vector<LaneChange> changes_;
  std::vector<double> ahead_speeds_;
  std::vector<double> behind_speeds_;
  std::vector<int> within_;
  double farthest_m_ = 0.0;
  int placements_ = 0;
  std::vector<double> first_frame_mps_;
  std::vector<int> parked_at_start_;
  double ego_distance_m_ = 0.0;
  double ego_duration_s_ = 0.0;
  double loop_length_m_ = 0.0;
};

/// What `overtake calibrate` runs.
struct CalibrateOptions {
  std::vector<std::uint64_t> seeds{1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  double minutes = 10.0;
  std::string policy = "reference";
  std::string traffic = "faithful";
  std::optional<std::filesystem::path> map;
  std::optional<std::filesystem::path> config;
  int jobs = 1;
};

/// Progress of a calibration: seeds finished of total, wall seconds elapsed.
struct CalibrationProgress {
  std::size_t done = 0;
  std::size_t total = 0;
  double wall_s = 0.0;
};

/// What a calibration measured.
struct Calibration {
  TrafficFigures figures;    ///< of the seeds that finished
  std::size_t runs = 0;      ///< seeds that finished
  bool interrupted = false;  ///< stopped before every seed finished
};

/// Drives every seed (in parallel on `jobs` threads) and measures the traffic as the planner
/// sees it, the seeds merged in their order (the same figures whatever the jobs). Throws
/// UsageError for bad options, std::runtime_error naming the seed when a run fails. `stop`
/// (may be null) is polled: when set, runs in progress are abandoned and the figures are
/// those of the seeds that finished.
[[nodiscard]] Calibration calibrate(
    const CalibrateOptions& opts, const std::atomic<bool>* stop = nullptr,
    const std::function<void(const CalibrationProgress&)>& progress = {});

/// One row of the comparison with the original.
struct CalibrationRow {
  std::string key;           ///< JSON key
  std::string statistic;     ///< what it measures
  std::string original;      ///< the original's figure (calibration data)
  std::string accept;        ///< accept range ("" when only shown)
  double value = 0.0;        ///< overtake's figure
  std::string shown;         ///< overtake's figure as printed
  std::optional<bool> pass;  ///< empty when there is no accept range
};

/// The comparison table: every figure beside the original's, with its accept range.
[[nodiscard]] std::vector<CalibrationRow> compare_with_original(const TrafficFigures& f);

/// The table as text (one row a line), and as JSON.
[[nodiscard]] std::string format_calibration(const std::vector<CalibrationRow>& rows);
[[nodiscard]] nlohmann::json calibration_to_json(const TrafficFigures& f,
                                                 const std::vector<CalibrationRow>& rows);

/// What `overtake calibrate` prints (the figures beside the original's) and writes to `json`
/// (when not empty); the exit status: 0 when every row passes, 1 when one fails, 130 when the
/// calibration was interrupted (the figures are those of the seeds that finished).
[[nodiscard]] int report_calibration(const CalibrateOptions& options, const Calibration& c,
                                     const std::filesystem::path& json);

}  // namespace overtake::batch
