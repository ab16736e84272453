// The `overtake calibrate` command line.

#include <cstdio>
#include <iostream>
#include <thread>

#include "overtake/app/cli.hpp"
#include "overtake/app/interrupt.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/batch/calibration.hpp"
#include "overtake/batch/pool.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"

namespace overtake::app {

using base::fixed_text;
using base::json_text;
using base::kExitFailure;
using base::kExitInterrupted;
using base::kExitOk;
using base::stderr_is_terminal;
using base::UsageError;
using base::write_file_atomic;
using batch::calibrate;
using batch::CalibrateOptions;
using batch::Calibration;
using batch::calibration_to_json;
using batch::CalibrationProgress;
using batch::CalibrationRow;
using batch::compare_with_original;
using batch::format_calibration;
using batch::parse_seed_list;
using batch::TrafficFigures;

namespace {

// A terminal gets one progress line drawn over; anything else (a log) a line per seed done.
void show_progress(const CalibrationProgress& p, std::size_t& shown) {
  if (stderr_is_terminal()) {
    std::fprintf(stderr, "\r  calibrate: %zu/%zu seeds, %.0f s   ", p.done, p.total, p.wall_s);
  } else if (p.done > shown) {
    std::fprintf(stderr, "calibrate: %zu of %zu seeds done\n", p.done, p.total);
  }
  std::fflush(stderr);
  shown = p.done;
}

// Drives the seeds under Ctrl-C: an interrupted calibration keeps the seeds that finished.
Calibration calibrate_here(const CalibrateOptions& o) {
  const InterruptScope interrupt;
  std::size_t shown = 0;
  Calibration c;
  try {
    c = calibrate(o, &InterruptScope::flag(),
                  [&](const CalibrationProgress& p) { show_progress(p, shown); });
  } catch (...) {
    if (stderr_is_terminal()) std::fprintf(stderr, "\n");
    throw;
  }
  if (stderr_is_terminal()) std::fprintf(stderr, "\n");
  return c;
}

// Prints the figures beside the original's and writes them as JSON; the exit status.
int report_calibration(const CalibrateOptions& o, const Calibration& c, const std::string& json) {
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
  if (!json.empty()) write_file_atomic(json, json_text(j, 2) + "\n");
  if (c.interrupted) {
    std::cerr << "calibrate: interrupted; the figures are those of the " << c.runs << " of "
              << o.seeds.size() << " seeds that finished\n";
    return kExitInterrupted;
  }
  return j["all_pass"].get<bool>() ? kExitOk : kExitFailure;
}

}  // namespace

Subcommand register_calibrate(CLI::App& app) {
  struct State {
    CalibrateOptions opts;
    std::string seeds = "1-10";
    std::string map, config, json;
  };
  auto st = std::make_shared<State>();
  st->opts.jobs = batch::default_jobs();
  auto* cmd = app.add_subcommand(
      "calibrate",
      "Measure the traffic as a planner observes it (from the sensor fusion it receives) over\n"
      "several seeds, beside the figures recorded from the original simulator, with pass/fail\n"
      "against the accept ranges (docs/fidelity.md). Exit status 1 when a row fails; 130 when\n"
      "interrupted (Ctrl-C: the figures of the seeds that finished are shown).");
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
            if (!(o.minutes > 0.0) || o.minutes > run::kMaxMinutes) {
              throw UsageError("--minutes must be more than 0 and at most " +
                               fixed_text(run::kMaxMinutes, 0));
            }
            return report_calibration(o, calibrate_here(o), st->json);
          }};
}

}  // namespace overtake::app
