#pragma once
// Quantiles of a stream of positive durations in fixed memory: a histogram with buckets
// whose bounds grow by 2% each, from 1 ns to about 16 hours. A quantile is reported as the
// geometric middle of its bucket, within 1% of the exact order statistic's value (relative
// error at most sqrt(g) - 1 = 0.995% for the bucket ratio g = 1.02); the maximum is kept
// exactly.
// Memory does not grow with the number of values (a 7-day run has 15 million cycles).

#include <array>
#include <cstdint>

namespace overtake::core {

class QuantileSketch {
 public:
  /// Bucket ratio and range (microseconds).
  static constexpr double kRatio = 1.02;
  static constexpr double kMinUs = 1e-3;
  static constexpr std::size_t kBuckets = 1600;  ///< 1.02^1600 * 1e-3 us ~ 5.8e10 us
  /// Largest relative error of a reported quantile (values inside the range): sqrt(1.02) - 1.
  static constexpr double kRelativeError = 0.01;

  /// Adds one value (microseconds). Values under the range count in the first bucket, over
  /// it in the last; NaN is ignored.
  void add(double us);
  /// The q-quantile (0 < q <= 1) as the nearest-rank order statistic, within kRelativeError;
  /// 0 when empty.
  [[nodiscard]] double quantile(double q) const;
  [[nodiscard]] double max() const { return max_; }
  [[nodiscard]] std::uint64_t count() const { return count_; }

 private:
  std::array<std::uint64_t, kBuckets> counts_{};
  std::uint64_t count_ = 0;
  double max_ = 0.0;
};

}  // namespace overtake::core
