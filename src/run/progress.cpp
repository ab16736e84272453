#include "overtake/run/progress.hpp"

#include <cstdio>

#include "overtake/base/io.hpp"
#include "overtake/core/units.hpp"

namespace overtake::run {

using base::stderr_is_terminal;

ProgressLine::ProgressLine(bool enabled, double total_s)
    : enabled_(enabled && stderr_is_terminal()), total_s_(total_s) {}

void ProgressLine::update(double t_s, double distance_m) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_ < std::chrono::milliseconds(100)) return;
  last_ = now;
  const double wall_s = std::chrono::duration<double>(now - start_).count();
  char total[32] = "";
  if (total_s_ > 0.0) std::snprintf(total, sizeof total, " / %.1f", total_s_ / 60.0);
  std::fprintf(stderr, "\r  %6.1f%s min simulated   %7.2f mi   %6.0fx real time ", t_s / 60.0,
               total, core::metres_to_miles(distance_m), wall_s > 0 ? t_s / wall_s : 0.0);
  std::fflush(stderr);
  shown_ = true;
}

void ProgressLine::clear() {
  if (!shown_) return;
  std::fprintf(stderr, "\r%80s\r", "");
  std::fflush(stderr);
  shown_ = false;
}

}  // namespace overtake::run
