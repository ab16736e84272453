// Calibration: the figures a planner observes of the traffic, measured from telemetry, and
// the faithful world against the accept ranges of the figures recorded from the original.

#include "overtake/batch/calibration.hpp"

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "overtake/base/io.hpp"
#include "overtake/core/units.hpp"
#include "overtake/run/config.hpp"
#include "process_support.hpp"
#include "temp_dir.hpp"

namespace overtake::batch {

namespace {

bool sanitized() {
  const char* v = std::getenv("OVERTAKE_SANITIZED");
  return v != nullptr && std::string(v) == "1";
}

/// A telemetry with the ego at s and cars given as (id, s, d, speed along +x).
core::Telemetry frame(double ego_s, const std::vector<std::array<double, 4>>& cars) {
  core::Telemetry t;
  t.ego.s_m = ego_s;
  t.ego.d_m = 6.0;
  for (const auto& c : cars) {
    core::CarObservation o;
    o.id = static_cast<int>(c[0]);
    o.s_m = c[1];
    o.d_m = c[2];
    o.position = {c[1], -c[2]};
    o.velocity_mps = {c[3], 0.0};
    t.cars.push_back(o);
  }
  return t;
}

TEST(TrafficObserver, MeasuresSpeedsNeighboursAndLaneChanges) {
  TrafficObserver obs(7000.0);
  obs.begin_run();
  const double v = core::mph_to_mps(40.0);
  // Car 0 drives 30 m ahead in lane 1; car 1 changes from lane 0 to lane 2 over 20 s,
  // 100 m behind; car 2 waits parked off the road.
  for (int k = 0; k <= 400; ++k) {
    const double t = 0.1 * k;
    const double ego_s = 100.0 + v * t;
    const double d1 = t < 5.0 ? 2.0 : t < 10.0 ? 6.0 : 10.0;
    obs.observe(
        t, frame(ego_s,
                 {{0, ego_s + 30.0, 6.0, v}, {1, ego_s - 100.0, d1, v}, {2, 6700.0, -280.0, 0.0}}));
  }
  obs.end_run(v * 40.0, 40.0);
  const TrafficFigures f = obs.figures();
  EXPECT_NEAR(f.speed_mean_mph, 40.0, 1e-6);
  EXPECT_NEAR(f.speed_p95_mph, 40.0, 1e-6);
  EXPECT_EQ(f.share_above_50_mph, 0.0);
  EXPECT_NEAR(f.car_minutes, 2.0 * 40.0 / 60.0, 0.05);  // two cars on the road for 40 s
  EXPECT_NEAR(f.lane_changes_per_car_minute, 2.0 / f.car_minutes, 1e-9);
  EXPECT_NEAR(f.within_60m_mean, 1.0, 1e-9);  // car 0 only
  EXPECT_NEAR(f.farthest_m, 100.0, 1e-6);
  EXPECT_NEAR(f.wander_max_m, 0.0, 1e-9);
  EXPECT_NEAR(f.hold_median_change_mph, 0.0, 1e-9);
  EXPECT_EQ(f.parked_at_start, 1.0);
  EXPECT_NEAR(f.ego_mean_speed_mph, 40.0, 1e-6);
}

TEST(TrafficObserver, SeesPlacementsAndTheirFirstFrame) {
  TrafficObserver obs(7000.0);
  obs.begin_run();
  const double v = 18.0;
  obs.observe(0.0, frame(100.0, {{0, 6700.0, -280.0, 0.0}}));  // parked at the start
  obs.observe(0.02, frame(100.0, {{0, 40.0, 6.0, 52.0}}));     // placed: its cap as m/s
  obs.observe(0.04, frame(100.0, {{0, 40.4, 6.0, v}}));
  obs.observe(0.06, frame(100.0, {{0, 400.0, 6.0, v}}));  // placed again, frame missed
  const TrafficFigures f = obs.figures();
  EXPECT_EQ(f.placements, 2);
  EXPECT_EQ(f.first_frames_seen, 1);
  EXPECT_DOUBLE_EQ(f.first_frame_min_mps, 52.0);
}

// The faithful world, as a planner observes it, against the figures recorded from the
// original (calibration data): every accept range holds over fixed seeds.
TEST(Calibration, TheFaithfulWorldMeetsEveryAcceptRange) {
  CalibrateOptions o;
  o.seeds =
      sanitized() ? std::vector<std::uint64_t>{1, 2} : std::vector<std::uint64_t>{1, 2, 3, 4, 5, 6};
  o.minutes = sanitized() ? 4.0 : 10.0;
  o.jobs = 2;
  const TrafficFigures f = calibrate(o).figures;
  const std::vector<CalibrationRow> rows = compare_with_original(f);
  std::cout << format_calibration(rows);
  int checked = 0;
  for (const CalibrationRow& r : rows) {
    if (!r.pass) continue;
    ++checked;
    EXPECT_TRUE(*r.pass) << r.statistic << ": " << r.shown << " (accept " << r.accept << ")";
  }
  EXPECT_GE(checked, 9);
  // And the figures the rows print agree with the table's numbers.
  EXPECT_GT(f.rows, 10000);
  EXPECT_GE(f.speed_mean_mph, 36.0);
  EXPECT_LE(f.speed_mean_mph, 42.5);
}

// Ctrl-C once a seed has finished (its progress line is on disk, not after a fixed time): the
// calibration stops, shows the figures of the seeds that finished, and says it was
// interrupted.
TEST(Calibration, CtrlCStopsItAndKeepsTheSeedsThatFinished) {
  namespace fs = std::filesystem;
  const test::TempDir dir;
  const fs::path err = dir.path() / "stderr";
  const fs::path json_file = dir.path() / "calibration.json";
  const pid_t pid = test::start_overtake({"calibrate", "--seeds", "1-1000", "--minutes", "5",
                                          "--jobs", "2", "--json", json_file.string()},
                                         dir.path() / "stdout", err);
  const auto until = std::chrono::steady_clock::now() + std::chrono::minutes(2);
  const auto a_seed_done = [&] {
    std::error_code ec;
    return fs::exists(err, ec) &&
           base::read_file(err, 1 << 20).find("seeds done") != std::string::npos;
  };
  while (!a_seed_done() && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(a_seed_done()) << base::read_file(err, 1 << 20);
  ::kill(pid, SIGINT);
  const auto status = test::exit_status(pid, std::chrono::minutes(1));
  ASSERT_TRUE(status.has_value()) << "calibrate did not end within a minute of Ctrl-C";
  EXPECT_EQ(*status, 130);
  const std::string said = base::read_file(err, 1 << 20);
  EXPECT_NE(said.find("calibrate: interrupted"), std::string::npos) << said;
  const nlohmann::json j = run::read_json_file(json_file);
  EXPECT_TRUE(j["interrupted"].get<bool>());
  const auto finished = j["seeds_finished"].get<std::size_t>();
  EXPECT_GE(finished, 1U);
  EXPECT_LT(finished, 1000U);
  EXPECT_GT(j["figures"]["rows"].get<long>(), 0);
  const std::string shown = base::read_file(dir.path() / "stdout", 1 << 20);
  EXPECT_NE(shown.find("overtake calibrate: " + std::to_string(finished) + " seeds"),
            std::string::npos)
      << shown;
}

}  // namespace
}  // namespace overtake::batch
