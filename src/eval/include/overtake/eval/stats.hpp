#pragma once
// Intervals and tests for bench figures, pure functions over numbers. Every figure is a ratio
// of sums over runs, one run per seed (mean speed: miles over hours; a rate: events over
// miles), and the seeds are the units that vary: a dense seed is slow for every planner, and
// the rubric's counts come in bursts within a seed (one contact counted each second it lasts).
// So every interval and test here takes the seed as its unit (docs/evaluation.md, "Intervals"
// and "Verdicts", says why each method and what its calibration measured):
//
// - a mean (ratio of sums): the bootstrap-t over seeds (Hall 1988), studentized by the
//   ratio's linearized (delta-method) standard error: the span of its symmetric and its
//   equal-tailed interval;
// - a rate with events: the exact (Garwood) gamma interval on the effective count K / phi,
//   phi the seeds' Pearson dispersion (at least 1) scaled by (t / z)^2 for its n - 1 degrees
//   of freedom (quasi-Poisson); with no event, the exact one-sided upper bound;
// - a median: the distribution-free interval between order statistics;
// - a paired difference of means: the same bootstrap-t over the seeds' pairs; of rates:
//   MOVER (Zou and Donner 2008) from the two rates' intervals and the seeds' correlation;
// - tests: the paired t-test (means), the exact sign-flip randomization test over seeds
//   (rates: Fisher's, exact for any distribution of counts within a seed), the Holm (1979)
//   correction over a family of tests;
// - the probability of improvement P(X > Y) over all pairs of runs (rliable, Agarwal et al.
//   2021) with a bootstrap interval over the seeds;
// - how many seeds would halve an interval, from the same methods.
//
// Generators are seeded from a key, so that the same rows always give the same numbers, byte
// for byte.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace overtake::eval {

/// A two-sided interval [lo, hi].
struct Interval {
  double lo = 0.0;
  double hi = 0.0;
  [[nodiscard]] double width() const { return hi - lo; }
  /// True when 0 lies strictly outside it.
  [[nodiscard]] bool excludes_zero() const { return lo > 0.0 || hi < 0.0; }
  friend bool operator==(const Interval&, const Interval&) = default;
};

inline constexpr double kConfidence = 0.95;
/// Resamples of every bootstrap interval the bench prints.
inline constexpr int kBootstrapResamples = 10000;
/// Below this many seeds no interval is given and no verdict: the intervals' coverage was
/// measured to hold from here (docs/evaluation.md, "Calibration"), and a paired difference of
/// fewer seeds is too little to judge.
inline constexpr std::size_t kMinSeeds = 8;
/// The family-wise error rate of the verdicts (Holm over every test one table judges).
inline constexpr double kFamilyAlpha = 0.05;

/// The exact (Garwood) interval for the mean of a Poisson variable of which `events` were
/// seen: [chi2(a/2; 2k) / 2, chi2(1 - a/2; 2k + 2) / 2], the lower end 0 for k = 0. `events`
/// may be fractional (an effective count). Throws std::invalid_argument for negative or
/// non-finite counts or a confidence outside (0, 1).
[[nodiscard]] Interval poisson_interval(double events, double confidence = kConfidence);

/// The exact one-sided upper bound of a Poisson mean after zero events: -ln(1 - confidence)
/// (3.00 at 95%).
[[nodiscard]] double poisson_zero_upper_bound(double confidence = kConfidence);

/// How a bootstrap draws: resamples, confidence, and the generator's seed.
struct BootstrapOptions {
  int resamples = kBootstrapResamples;
  double confidence = kConfidence;
  std::uint64_t seed = 0;
};

/// A generator seed derived from a text key (FNV-1a), so that an interval depends only on
/// what it is of (e.g. "mean_speed_mph|reference|faithful") and its data.
[[nodiscard]] std::uint64_t bootstrap_seed(std::string_view key);

/// The `q` quantile (0-1) of values, linear between order statistics (sorts a copy).
[[nodiscard]] double quantile(std::vector<double> values, double q);
/// The median (0 for no values).
[[nodiscard]] double median(std::vector<double> values);

/// The bootstrap-t interval of sum(num) / sum(den) over seeds (one value of each per seed;
/// den > 0 overall), studentized by the linearized standard error se = sqrt(sum(z^2) / (n (n -
/// 1))), z_i = (num_i - R den_i) / mean(den): the span of the symmetric interval (R plus or
/// minus the confidence quantile of |t*| times se) and the equal-tailed one (R - t*(1 - a/2)
/// se, R - t*(a/2) se), every quantile at most twice Student's t(n - 1). The equal-tailed
/// interval follows a skewed spread (a few slow seeds), the symmetric one holds when the
/// studentized spread is itself poorly estimated; their span held its coverage on every real
/// shape measured (docs/evaluation.md). Fewer than two seeds, or no spread: [R, R].
[[nodiscard]] Interval mean_interval(std::span<const double> num, std::span<const double> den,
                                     const BootstrapOptions& options);

/// A rate's interval over seeds: events and exposure per seed, the rate per `per` units of
/// exposure.
struct RateInterval {
  Interval ci;
  /// True when no event was seen: `ci` is [0, the one-sided upper bound] at the confidence.
  bool upper_bound_only = false;
  /// The dispersion the interval used (1: as Poisson; 0 with no event).
  double dispersion = 0.0;
  /// The largest share of the events one seed holds (0 with no event), and how many that is:
  /// a burst of many in one seed makes the rate that seed's, and no interval from the others
  /// can tell how rare such seeds are.
  double top_seed_share = 0.0;
  double top_seed_events = 0.0;
};

/// The overdispersed exact interval of a rate over seeds (quasi-Poisson): with K > 0 events in
/// exposure M, phi = max(1, Pearson X^2 / (n - 1)) * (t(n-1) / z)^2 and the Garwood interval of
/// K / phi events, times phi / M; with none, [0, -ln(1 - confidence) / M] (one-sided). Zero
/// exposure: [0, 0]. Throws std::invalid_argument for unequal lengths or negative values.
[[nodiscard]] RateInterval rate_interval(std::span<const double> events,
                                         std::span<const double> exposure, double per,
                                         double confidence = kConfidence);

/// The distribution-free interval of a median: the order statistics x(k) and x(n + 1 - k)
/// with the largest k for which the binomial coverage is at least the confidence (for n = 20:
/// the 6th and 15th, 95.9%). Fewer values than that needs: the smallest and largest.
[[nodiscard]] Interval median_interval(std::span<const double> values,
                                       double confidence = kConfidence);

/// Two arms over the same seeds (index i of each is one seed): a figure sum(num) / sum(den)
/// for each.
struct PairedRatios {
  std::span<const double> num_a, den_a, num_b, den_b;
};

/// The bootstrap-t interval (as mean_interval) of the paired difference of two ratios of
/// sums, A - B, the seeds resampled with both arms, studentized by the linearized standard
/// error of the difference.
[[nodiscard]] Interval mean_difference_interval(const PairedRatios& pairs,
                                                const BootstrapOptions& options);

/// The two-sided paired t-test of the same difference (its linearized per-seed terms):
/// p-value with n - 1 degrees of freedom; 1 when it has no spread and no difference, 0 when it
/// has no spread and a difference.
[[nodiscard]] double mean_difference_p_value(const PairedRatios& pairs);

/// The difference of two rates (per `per` units of exposure) over paired seeds, A - B, by
/// MOVER: each arm's rate_interval (two-sided: the exact upper end after zero events) and the
/// correlation r of the seeds' residuals: [D - sqrt(dl_a^2 + du_b^2 - 2 r dl_a du_b),
/// D + sqrt(du_a^2 + dl_b^2 - 2 r du_a dl_b)].
[[nodiscard]] Interval rate_difference_interval(const PairedRatios& pairs, double per,
                                                double confidence = kConfidence);

/// The exact two-sided sign-flip randomization test of paired rate differences: the
/// statistic sum_i w_i (a_i / da_i - b_i / db_i) with w_i = (da_i + db_i) / 2, against every
/// assignment of the two runs of each seed to the arms: all 2^m when m <= 16 seeds differ,
/// else a seeded Monte Carlo of at most `monte_carlo` draws, p = (exceedances + 1) / (draws +
/// 1), stopped once 20 draws were as extreme (p = 20 / draws, Besag and Clifford 1991). Seeds
/// without exposure in an arm are left out. 1 when no seed differs.
[[nodiscard]] double rate_difference_p_value(const PairedRatios& pairs, std::uint64_t seed,
                                             int monte_carlo = 20000);

/// Holm's step-down adjustment of p-values (each at most 1, monotone in the sorted order).
[[nodiscard]] std::vector<double> holm_adjust(std::span<const double> p_values);

/// The probability of improvement with its interval.
struct Improvement {
  double p = 0.5;
  Interval ci{0.5, 0.5};
};

/// rliable's probability of improvement: P(X > Y) over every pair of a run of A (x) and a run
/// of B (y), ties counting half, with "better" as higher or lower as said; its interval a
/// percentile bootstrap over the seeds (x_i and y_i are one seed's runs, resampled together).
/// 0.5 for no runs.
[[nodiscard]] Improvement probability_of_improvement(std::span<const double> x,
                                                     std::span<const double> y,
                                                     bool higher_is_better,
                                                     const BootstrapOptions& options);

/// Seeds that would halve a bootstrap-t interval of `seeds` seeds if the spread stayed as it
/// is (its half width goes as t(n - 1) / sqrt(n)).
[[nodiscard]] std::size_t seeds_to_halve_mean(std::size_t seeds);

/// Seeds that would halve a rate's interval of `seeds` seeds if the events per seed and
/// their dispersion stayed as they are (no event: twice the exposure halves the bound).
[[nodiscard]] std::size_t seeds_to_halve_rate(std::span<const double> events,
                                              std::span<const double> exposure,
                                              double confidence = kConfidence);

}  // namespace overtake::eval
