#pragma once
// The progress line of a long run on a terminal (stderr).

#include <chrono>

namespace overtake::run {

/// One status line on a terminal, redrawn at most ten times a second: simulated minutes (of
/// the total when known), miles, and the real-time factor. Silent when disabled or when
/// stderr is not a terminal. Clears itself when destroyed.
class ProgressLine {
 public:
  /// `total_s`: the run's simulated length when known, else 0.
  explicit ProgressLine(bool enabled, double total_s = 0.0);
  ~ProgressLine() { clear(); }
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  void update(double t_s, double distance_m);
  void clear();

 private:
  bool enabled_;
  double total_s_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace overtake::run
