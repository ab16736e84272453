// The `overtake calibrate` command line.

#include <cstdio>
#include <iostream>

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
using base::UsageError;
using batch::calibrate;
using batch::CalibrateOptions;
using batch::Calibration;
using batch::CalibrationProgress;
using batch::parse_seed_list;
using batch::report_calibration;

namespace {

// A terminal gets one progress line drawn over; anything else (a log) a line per seed done.
void show_progress(base::StatusLine& line, const CalibrationProgress& p, std::size_t& shown) {
  if (line.on()) {
    line.draw("  calibrate: " + std::to_string(p.done) + "/" + std::to_string(p.total) +
              " seeds, " + fixed_text(p.wall_s, 0) + " s   ");
  } else if (p.done > shown) {
    std::fprintf(stderr, "calibrate: %zu of %zu seeds done\n", p.done, p.total);
  }
  shown = p.done;
}

// Drives the seeds under Ctrl-C: an interrupted calibration keeps the seeds that finished.
Calibration calibrate_here(const CalibrateOptions& o) {
  base::StatusLine line(true);
  const InterruptScope interrupt;
  std::size_t shown = 0;
  return calibrate(o, &InterruptScope::flag(),
                   [&](const CalibrationProgress& p) { show_progress(line, p, shown); });
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
