#include "overtake/eval/stats.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <boost/math/special_functions/gamma.hpp>

#include "overtake/core/random.hpp"

namespace overtake::eval {
namespace {

void check_confidence(double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) {
    throw std::invalid_argument("confidence must be between 0 and 1 (got " +
                                std::to_string(confidence) + ")");
  }
}

/// A uniform index in [0, n) (n > 0).
std::size_t draw_index(core::Rng& rng, std::size_t n) {
  return static_cast<std::size_t>(rng.next() % n);
}

/// The `q` quantile of sorted values, linear between order statistics.
double sorted_quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0.0;
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(sorted.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (pos - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

/// The percentile interval of bootstrap statistics (sorted in place).
Interval percentile_interval(std::vector<double>& stats, double confidence) {
  const double alpha = 1.0 - confidence;
  std::sort(stats.begin(), stats.end());
  return {sorted_quantile(stats, 0.5 * alpha), sorted_quantile(stats, 1.0 - 0.5 * alpha)};
}

void check_options(const BootstrapOptions& o) {
  check_confidence(o.confidence);
  if (o.resamples < 1) throw std::invalid_argument("a bootstrap needs at least one resample");
}

double ratio(double num, double den) {
  return den > 0.0 ? num / den : 0.0;
}

}  // namespace

Interval poisson_interval(double events, double confidence) {
  check_confidence(confidence);
  if (!(events >= 0.0) || !std::isfinite(events)) {
    throw std::invalid_argument("a Poisson count must be finite and at least 0 (got " +
                                std::to_string(events) + ")");
  }
  const double alpha = 1.0 - confidence;
  // chi2(p; 2k) / 2 is the p quantile of a Gamma(k, 1) variable.
  const double lo = events > 0.0 ? boost::math::gamma_p_inv(events, 0.5 * alpha) : 0.0;
  const double hi = boost::math::gamma_p_inv(events + 1.0, 1.0 - 0.5 * alpha);
  return {lo, hi};
}

Interval rate_interval(double events, double exposure, double per, double confidence) {
  const Interval counts = poisson_interval(events, confidence);
  if (!(exposure > 0.0)) return {0.0, 0.0};
  return {counts.lo / exposure * per, counts.hi / exposure * per};
}

std::uint64_t bootstrap_seed(std::string_view key) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : key) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return h;
}

double quantile(std::vector<double> values, double q) {
  std::sort(values.begin(), values.end());
  return sorted_quantile(values, q);
}

double median(std::vector<double> values) {
  return quantile(std::move(values), 0.5);
}

Interval bootstrap_ratio(std::span<const double> num, std::span<const double> den,
                         const BootstrapOptions& o) {
  check_options(o);
  if (num.size() != den.size()) throw std::invalid_argument("bootstrap_ratio: unequal lengths");
  const std::size_t n = num.size();
  if (n == 0) return {};
  core::Rng rng(o.seed);
  std::vector<double> stats(static_cast<std::size_t>(o.resamples));
  for (double& s : stats) {
    double a = 0.0, b = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = draw_index(rng, n);
      a += num[i];
      b += den[i];
    }
    s = ratio(a, b);
  }
  return percentile_interval(stats, o.confidence);
}

Interval bootstrap_median(std::span<const double> values, const BootstrapOptions& o) {
  check_options(o);
  const std::size_t n = values.size();
  if (n == 0) return {};
  core::Rng rng(o.seed);
  std::vector<double> stats(static_cast<std::size_t>(o.resamples));
  std::vector<double> sample(n);
  for (double& s : stats) {
    for (double& v : sample) v = values[draw_index(rng, n)];
    const auto mid = sample.begin() + static_cast<std::ptrdiff_t>(n / 2);
    std::nth_element(sample.begin(), mid, sample.end());
    if (n % 2) {
      s = *mid;
    } else {
      const double upper = *mid;
      const double lower = *std::max_element(sample.begin(), mid);
      s = 0.5 * (lower + upper);
    }
  }
  return percentile_interval(stats, o.confidence);
}

Interval bootstrap_ratio_difference(std::span<const double> num_a, std::span<const double> den_a,
                                    std::span<const double> num_b, std::span<const double> den_b,
                                    const BootstrapOptions& o) {
  check_options(o);
  const std::size_t n = num_a.size();
  if (den_a.size() != n || num_b.size() != n || den_b.size() != n) {
    throw std::invalid_argument("bootstrap_ratio_difference: unequal lengths");
  }
  if (n == 0) return {};
  core::Rng rng(o.seed);
  std::vector<double> stats(static_cast<std::size_t>(o.resamples));
  for (double& s : stats) {
    double na = 0.0, da = 0.0, nb = 0.0, db = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = draw_index(rng, n);
      na += num_a[i];
      da += den_a[i];
      nb += num_b[i];
      db += den_b[i];
    }
    s = ratio(na, da) - ratio(nb, db);
  }
  return percentile_interval(stats, o.confidence);
}

double probability_of_improvement(std::span<const double> a, std::span<const double> b,
                                  bool higher_is_better) {
  if (a.size() != b.size()) {
    throw std::invalid_argument("probability_of_improvement: unequal lengths");
  }
  if (a.empty()) return 0.5;
  double wins = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i] == b[i]) {
      wins += 0.5;
    } else if ((a[i] > b[i]) == higher_is_better) {
      wins += 1.0;
    }
  }
  return wins / static_cast<double>(a.size());
}

std::size_t seeds_to_halve_bootstrap(std::size_t runs) {
  return 4 * runs;
}

std::size_t seeds_to_halve_rate(double events, std::size_t runs, double confidence) {
  if (runs == 0) return 0;
  // With f times the exposure, the count is f k and the rate's width (U(f k) - L(f k)) / f.
  const auto width = [&](double f) {
    const Interval i = poisson_interval(events * f, confidence);
    return i.width() / f;
  };
  const double target = 0.5 * width(1.0);
  double lo = 1.0, hi = 2.0;
  while (width(hi) > target && hi < 1e6) hi *= 2.0;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (width(mid) > target ? lo : hi) = mid;
  }
  return static_cast<std::size_t>(std::ceil(hi * static_cast<double>(runs) - 1e-9));
}

}  // namespace overtake::eval
