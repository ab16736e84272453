#include "overtake/batch/progress.hpp"

#include <cstdio>

#include "overtake/base/text.hpp"
#include "overtake/core/units.hpp"

namespace overtake::batch {

namespace {

template <typename... Args>
std::string formatted(const char* format, Args... args) {
  char buf[512];
  // NOLINTNEXTLINE(cppcoreguidelines-pro-type-vararg): the formats are this file's own
  std::snprintf(buf, sizeof buf, format, args...);
  return buf;
}

}  // namespace

std::string duration_text(double s) {
  if (s >= 3600)
    return formatted("%dh%02dm", static_cast<int>(s / 3600), static_cast<int>(s / 60) % 60);
  if (s >= 60) return formatted("%dm%02ds", static_cast<int>(s / 60), static_cast<int>(s) % 60);
  return formatted("%ds", static_cast<int>(s));
}

std::string progress_text(const BenchProgress& p, double total_sim_s) {
  constexpr int kWidth = 24;
  const double frac = p.total ? static_cast<double>(p.done) / static_cast<double>(p.total) : 1.0;
  const int filled = static_cast<int>(frac * kWidth);
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.resize(kWidth, '.');
  std::string eta = "--";
  if (p.simulated_s > 0 && total_sim_s > p.simulated_s) {
    eta = duration_text(p.wall_s * (total_sim_s - p.simulated_s) / p.simulated_s);
  } else if (p.done >= p.total) {
    eta = "0s";
  }
  return formatted("  [%s] %zu/%zu runs  %9.1f mi simulated  elapsed %s  ETA %s   ", bar.c_str(),
                   p.done, p.total, core::metres_to_miles(p.simulated_m),
                   duration_text(p.wall_s).c_str(), eta.c_str());
}

std::string progress_text(const HuntProgress& p) {
  const double rate = p.wall_s > 0 ? (p.simulated_s / 3600.0) / (p.wall_s / 60.0) : 0;
  const double left_s =
      p.simulated_s > 0 ? p.wall_s * (p.budget_s - p.simulated_s) / p.simulated_s : 0;
  return formatted(
      "  hunt: %zu runs, %.1f of %.1f simulated h, %zu failures in %zu situations, %.1f "
      "sim-h/min, at most %.0f s to go   ",
      p.runs, p.simulated_s / 3600.0, p.budget_s / 3600.0, p.failures, p.groups, rate, left_s);
}

std::string progress_text(const RiskProgress& p) {
  return formatted(
      "  risk: %zu runs, %.1f of %.1f simulated h, %.2f weighted events, %.4f per 100 mi "
      "(+-%.0f%%), %.0f s   ",
      p.runs, p.simulated_h, p.budget_h, p.weighted_events, p.rate_per_100mi,
      100.0 * p.rel_half_width, p.wall_s);
}

std::string progress_text(const TuneProgress& p) {
  const std::string best = p.best ? ", best " + base::fixed_text(*p.best, 3) : std::string();
  return formatted("  tune: trial %d of %d, run %zu/%zu%s   ", p.trial, p.trials, p.runs_done,
                   p.runs_total, best.c_str());
}

}  // namespace overtake::batch
