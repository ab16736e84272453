#include "overtake/core/quantile_sketch.hpp"

#include <algorithm>
#include <cmath>

namespace overtake::core {
namespace {

const double kLogRatio = std::log(QuantileSketch::kRatio);

std::size_t bucket_of(double us) {
  if (!(us > QuantileSketch::kMinUs)) return 0;
  const double i = std::floor(std::log(us / QuantileSketch::kMinUs) / kLogRatio);
  return static_cast<std::size_t>(std::min(i, static_cast<double>(QuantileSketch::kBuckets - 1)));
}

}  // namespace

void QuantileSketch::add(double us) {
  if (std::isnan(us)) return;
  ++counts_[bucket_of(us)];
  ++count_;
  max_ = std::max(max_, us);
}

double QuantileSketch::quantile(double q) const {
  if (count_ == 0) return 0.0;
  const auto rank = static_cast<std::uint64_t>(
      std::clamp(std::ceil(q * static_cast<double>(count_)), 1.0, static_cast<double>(count_)));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < kBuckets; ++i) {
    seen += counts_[i];
    if (seen >= rank) {
      // The bucket [min g^i, min g^(i+1)): its geometric middle, never above the maximum.
      const double mid = kMinUs * std::pow(kRatio, static_cast<double>(i) + 0.5);
      return std::min(mid, max_);
    }
  }
  return max_;
}

}  // namespace overtake::core
