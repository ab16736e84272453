#pragma once
// Multilevel splitting for the rate of a rare event in a long run (RESTART, Villén-Altamirano
// and Villén-Altamirano 1991, 2011), over any system that can save its state, go on from a
// saved state with fresh random draws, and say how near it is to the event (its importance
// score). Pure engine: no files, no world; `overtake risk` runs it over the simulator
// (batch/risk.hpp), the tests over a Markov chain whose rate is known exactly.
//
// One base run is one plain run of the system. Thresholds L_1 < ... < L_m on the score cut
// its range into levels. When a path's score goes up through L_j, R_j - 1 copies of it are
// made there (each going on with fresh random draws) and all R_j go on; a copy made at L_j is
// ended when its score falls back below L_j, the path it was copied from is not. An event
// seen by a path while its score is at level k counts 1 / (R_1 ... R_k). The weighted count
// of a base run has the expectation of the plain count (docs/evaluation.md, "Rare events"),
// so the rate is the weighted events over the base runs' exposure.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "overtake/eval/stats.hpp"

namespace overtake::eval {

/// The levels: thresholds on the score, increasing, and how many paths go on from each
/// up-crossing (1: no split there).
struct SplitLevels {
  std::vector<double> thresholds;
  std::vector<int> splits;
  /// Throws std::invalid_argument naming what is wrong (unsorted, sizes, splits < 1).
  void validate() const;
  /// How many thresholds `score` is at or above.
  [[nodiscard]] int level_of(double score) const;
};

/// What one step of a path did.
struct SplitStep {
  double score = 0.0;   ///< the importance score after the step (higher: nearer the event)
  int events = 0;       ///< events that began in the step
  double exposure = 0;  ///< how far the path went in it (e.g. metres)
  double cost = 0;      ///< what it cost (e.g. simulated seconds)
  bool ended = false;   ///< the run is over (its duration, or the system stopped)
  double at = 0.0;      ///< the system's clock after the step (e.g. simulated seconds)
};

/// A system splitting can run: one path at a time, saved and restored by handle.
class SplitSystem {
 public:
  virtual ~SplitSystem() = default;
  /// The score of the state the path is in now.
  [[nodiscard]] virtual double score() = 0;
  /// Saves the path's state; returns a handle for restore.
  [[nodiscard]] virtual std::size_t save() = 0;
  /// Puts the path back into a saved state; with `reseed`, its random draws from there on
  /// are fresh ones from that seed (a copy), without, the same as the saved path's would
  /// have been (the path goes on as if never interrupted).
  virtual void restore(std::size_t handle, std::optional<std::uint64_t> reseed) = 0;
  /// Forgets a saved state.
  virtual void release(std::size_t handle) = 0;
  /// Advances the path one step.
  [[nodiscard]] virtual SplitStep advance() = 0;
};

/// An event, where it happened in the tree of paths.
struct SplitEvent {
  double weight = 0.0;     ///< what it counts
  int level = 0;           ///< the path's level when it happened
  std::size_t path = 0;    ///< the path's number in the base run (0: the base path)
  double base_cost = 0.0;  ///< the base path's cost when the branch it is in was made
  double at = 0.0;         ///< the system's clock after the step it happened in
};

/// One base run's tally.
struct SplitTally {
  double weighted_events = 0.0;  ///< Y: the run's estimate of the plain count
  int base_events = 0;           ///< the events of the base path alone (a plain run's count)
  double exposure = 0.0;         ///< M: the base path's
  double cost = 0.0;             ///< every path's
  double base_cost = 0.0;        ///< the base path's
  std::size_t paths = 1;         ///< the base path and every copy
  /// Per level j (0-based, threshold j): weighted up-crossings, i.e. the run's estimate of
  /// the plain number of times the score went up through L_j.
  std::vector<double> crossings;
  std::vector<SplitEvent> events;
};

/// Limits of one base run.
struct SplitLimits {
  /// A base run that would make more paths than this is an error (the splits are too many
  /// for the score: lower them).
  std::size_t max_paths = 200000;
  /// Seed of the copies' draws: copy n of the run gets derive_seed(seed, n).
  std::uint64_t seed = 0;
};

/// Raised when a base run makes more than SplitLimits::max_paths paths.
struct SplitExplosion : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Runs one base run of `system` (in its initial state) with splitting at `levels`.
[[nodiscard]] SplitTally run_split(SplitSystem& system, const SplitLevels& levels,
                                   const SplitLimits& limits);

/// The rate of the event per unit exposure from independent base runs: sum Y / sum M, with
/// its delta-method variance sum (Y_i - R M_i)^2 / (sum M)^2 * n / (n - 1), and a 95%
/// interval: the Garwood interval of the effective count R^2 / V (the count a Poisson
/// variable of that relative variance holds), its variance scaled by (t(n-1) / z)^2, times
/// R over that count. With no weighted event: the one-sided bound of the base runs as plain
/// runs (-ln 0.05 / sum M). Throws std::invalid_argument for unequal lengths or negative
/// values.
struct SplitEstimate {
  double rate = 0.0;
  Interval ci;
  bool upper_bound_only = false;
  double variance = 0.0;        ///< of the rate
  double effective_events = 0;  ///< R^2 / V (0 with no event)
  std::size_t runs = 0;
  std::size_t runs_with_events = 0;
};
[[nodiscard]] SplitEstimate split_estimate(std::span<const double> weighted_events,
                                           std::span<const double> exposure,
                                           double confidence = kConfidence);

/// A rate as a risk estimate gives it: the estimate and its 95% interval ([0, bound] with no
/// event).
struct RateEstimate {
  double rate = 0.0;
  Interval ci;
  bool upper_bound_only = false;
};

/// The ratio of two independent rates (candidate / base) with its 95% interval by MOVER on
/// the log scale (Zou and Donner 2008; the family of the bench's rate difference) from the
/// two intervals: log r -+ sqrt of the squared distances from each log estimate to its
/// interval's ends. A rate with no event gives a one-sided end (base none: [lo_c / hi_b,
/// infinity); candidate none: [0, hi_c / lo_b]); both none: no interval. The verdict:
/// "higher" or "lower" when the interval excludes 1, else "no difference"; "no verdict" when
/// there is no interval.
struct RateRatio {
  double ratio = 0.0;  ///< 0 when undefined (base without events)
  Interval ci;
  bool defined = true;  ///< false: the ratio itself is not (the base saw no event)
  std::string verdict;
};
[[nodiscard]] RateRatio rate_ratio(const RateEstimate& base, const RateEstimate& candidate);

}  // namespace overtake::eval
