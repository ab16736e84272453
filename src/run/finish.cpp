#include "overtake/run/finish.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>
#include <thread>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/run/report.hpp"
#include "overtake/view/server.hpp"

namespace overtake::run {

using base::json_text;
using base::kExitFailure;
using base::kExitInterrupted;
using base::kExitOk;

int finish_drive(const DriveResult& result, const DriveOptions& opts, const DriveOutputs& out,
                 const std::atomic<bool>* stop) {
  std::cout << format_scorecard(result.report, result.provenance);
  if (!out.quiet) {
    std::printf("  wall time          %.2f s (%.1fx real time%s%s)\n", out.wall_s,
                out.wall_s > 0 ? result.report.duration_s / out.wall_s : 0.0,
                out.mode.empty() ? "" : ", ", out.mode.c_str());
  }
  std::cout.flush();
  if (out.json) {
    base::write_file_atomic(*out.json,
                            json_text(report_to_json(result.report, result.provenance), 2) + "\n");
    if (!out.quiet) std::cout << "  report written to " << out.json->string() << "\n";
  }
  if (opts.record && !out.quiet)
    std::cout << "  replay written to " << opts.record->string() << "\n";
  base::flush_stdout_or_throw();  // now: a live view may keep the process up until Ctrl-C
  switch (result.report.outcome.end) {
    case sim::RunEnd::stopped:
      return kExitInterrupted;
    case sim::RunEnd::planner_failed:
      return kExitFailure;
    case sim::RunEnd::completed:
      break;
  }
  if (result.live) {
    std::fprintf(stderr, "the run is over; the live view stays at %s until Ctrl-C\n",
                 result.live->url().c_str());
    while (stop != nullptr && !stop->load())
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return kExitOk;
}

}  // namespace overtake::run
