#pragma once
// Intervals for bench figures, pure functions over numbers:
//
// - exact (Garwood 1936) Poisson intervals for event counts, and rates per exposure built on
//   them ("0 incidents in 440 miles" is 0 per 100 miles, 95% interval 0-0.84);
// - percentile bootstrap intervals over runs (Efron and Tibshirani 1993), for ratios of sums
//   (mean speed: miles over hours), medians, and paired differences of two ratios over the
//   same resampled seeds — with a generator seeded from a key, so that the same runs always
//   give the same interval, byte for byte;
// - the probability of improvement (rliable's P(X > Y), Agarwal et al. 2021), for pairs;
// - how many seeds (or how much exposure) would halve an interval's width.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace overtake::eval {

/// A two-sided interval [lo, hi].
struct Interval {
  double lo = 0.0;
  double hi = 0.0;
  [[nodiscard]] double width() const { return hi - lo; }
  /// True when 0 lies strictly outside it (a difference beyond noise).
  [[nodiscard]] bool excludes_zero() const { return lo > 0.0 || hi < 0.0; }
  friend bool operator==(const Interval&, const Interval&) = default;
};

inline constexpr double kConfidence = 0.95;
/// Resamples of every bootstrap interval the bench prints.
inline constexpr int kBootstrapResamples = 10000;

/// The exact (Garwood) interval for the mean of a Poisson variable of which `events` were
/// seen: [chi2(a/2; 2k) / 2, chi2(1 - a/2; 2k + 2) / 2], the lower end 0 for k = 0. `events`
/// may be fractional (used to ask how an interval shrinks with more exposure). Throws
/// std::invalid_argument for negative or non-finite counts or a confidence outside (0, 1).
[[nodiscard]] Interval poisson_interval(double events, double confidence = kConfidence);

/// The exact interval of a rate: events per `per` units of exposure (e.g. incidents per 100
/// miles). Zero exposure gives [0, 0].
[[nodiscard]] Interval rate_interval(double events, double exposure, double per,
                                     double confidence = kConfidence);

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

/// Percentile bootstrap interval of sum(num) / sum(den) over runs resampled with replacement
/// (den > 0 overall; a resample whose den sums to 0 counts as 0).
[[nodiscard]] Interval bootstrap_ratio(std::span<const double> num, std::span<const double> den,
                                       const BootstrapOptions& options);

/// Percentile bootstrap interval of the median of `values`.
[[nodiscard]] Interval bootstrap_median(std::span<const double> values,
                                        const BootstrapOptions& options);

/// Percentile bootstrap interval of a paired difference of ratios, sum(num_a) / sum(den_a) -
/// sum(num_b) / sum(den_b), the pairs (index i of each) resampled together. All four spans
/// have one length (the number of pairs).
[[nodiscard]] Interval bootstrap_ratio_difference(std::span<const double> num_a,
                                                  std::span<const double> den_a,
                                                  std::span<const double> num_b,
                                                  std::span<const double> den_b,
                                                  const BootstrapOptions& options);

/// The share of pairs on which a is better than b (higher or lower, as said), ties counting
/// half; 0.5 for no pairs.
[[nodiscard]] double probability_of_improvement(std::span<const double> a,
                                                std::span<const double> b, bool higher_is_better);

/// Seeds needed to halve a bootstrap interval of `runs` runs (width shrinks as 1/sqrt(n)).
[[nodiscard]] std::size_t seeds_to_halve_bootstrap(std::size_t runs);

/// Seeds needed to halve the exact interval of a rate seen as `events` in `runs` runs, if
/// the rate and the exposure per run stay as they are.
[[nodiscard]] std::size_t seeds_to_halve_rate(double events, std::size_t runs,
                                              double confidence = kConfidence);

}  // namespace overtake::eval
