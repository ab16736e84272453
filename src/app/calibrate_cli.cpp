// The `overtake calibrate` command line.

#include <cstdio>
#include <iostream>
#include <thread>

#include "overtake/app/bench.hpp"
#include "overtake/app/calibration.hpp"
#include "overtake/app/cli.hpp"
#include "overtake/app/commands.hpp"
#include "overtake/app/io.hpp"

namespace overtake::app {

Subcommand register_calibrate(CLI::App& app) {
  struct State {
    CalibrateOptions opts;
    std::string seeds = "1-10";
    std::string map, config, json;
  };
  auto st = std::make_shared<State>();
  st->opts.jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  auto* cmd = app.add_subcommand(
      "calibrate",
      "Measure the traffic as a planner observes it (from the sensor fusion it receives) over\n"
      "several seeds, beside the figures recorded from the original simulator, with pass/fail\n"
      "against the accept ranges (docs/fidelity.md). Exit status 1 when a row fails.");
  cmd->add_option("--seeds", st->seeds, "Seeds: a range and/or list, e.g. 1-10 or 1,5,9-12")
      ->capture_default_str();
  cmd->add_option("--minutes", st->opts.minutes, "Simulated minutes per seed")
      ->capture_default_str();
  cmd->add_option("--policy", st->opts.policy,
                  "Policy that drives the ego (it shapes the traffic around it)")
      ->capture_default_str();
  cmd->add_option("--traffic", st->opts.traffic, "Traffic profile (faithful, calm)")
      ->capture_default_str();
  cmd->add_option("--map", st->map, "Map file; default: the built-in track")
      ->check(CLI::ExistingFile);
  cmd->add_option("--config", st->config, "JSON file overriding default parameters")
      ->check(CLI::ExistingFile);
  cmd->add_option("--jobs,-j", st->opts.jobs, "Runs in parallel (default: all cores)")
      ->capture_default_str();
  cmd->add_option("--json", st->json,
                  "Also write the figures and the comparison as JSON to this file");
  return {cmd, [st] {
            CalibrateOptions o = st->opts;
            o.seeds = parse_seed_list(st->seeds);
            if (!st->map.empty()) o.map = st->map;
            if (!st->config.empty()) o.config = st->config;
            if (!(o.minutes > 0.0) || o.minutes > 7.0 * 24 * 60) {
              throw UsageError("--minutes must be more than 0 and at most 10080");
            }
            const TrafficFigures f = calibrate(o);
            const std::vector<CalibrationRow> rows = compare_with_original(f);
            std::printf(
                "overtake calibrate: %zu seeds x %g min, policy %s, %s traffic, %ld rows (%.0f "
                "car-minutes)\n",
                o.seeds.size(), o.minutes, o.policy.c_str(), o.traffic.c_str(), f.rows,
                f.car_minutes);
            std::cout << format_calibration(rows);
            std::cout.flush();
            const nlohmann::json j = calibration_to_json(f, rows);
            if (!st->json.empty()) write_file_atomic(st->json, json_text(j, 2) + "\n");
            return j["all_pass"].get<bool>() ? kExitOk : kExitFailure;
          }};
}

}  // namespace overtake::app
