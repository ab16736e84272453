#include "overtake/eval/stats.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include <boost/math/distributions/binomial.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <boost/math/special_functions/gamma.hpp>

#include "overtake/core/random.hpp"

namespace overtake::eval {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// Resamples of a probability of improvement's interval (each one sorts the runs).
constexpr int kImprovementResamples = 2000;
/// Up to this many seeds that differ, the sign-flip test enumerates every assignment.
constexpr std::size_t kExactFlipSeeds = 16;
/// A Monte Carlo sign-flip test stops once this many draws were as extreme as the data.
constexpr std::uint64_t kStopExceedances = 20;

void check_confidence(double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) {
    throw std::invalid_argument("confidence must be between 0 and 1 (got " +
                                std::to_string(confidence) + ")");
  }
}

void check_options(const BootstrapOptions& o) {
  check_confidence(o.confidence);
  if (o.resamples < 1) throw std::invalid_argument("a bootstrap needs at least one resample");
}

void check_lengths(std::size_t a, std::size_t b, const char* what) {
  if (a != b) throw std::invalid_argument(std::string(what) + ": unequal lengths");
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
  if (sorted[lo] == sorted[hi]) return sorted[lo];  // also two infinities
  return sorted[lo] + (pos - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

double ratio(double num, double den) {
  return den > 0.0 ? num / den : 0.0;
}

double sum(std::span<const double> v) {
  return std::accumulate(v.begin(), v.end(), 0.0);
}

/// Student's t quantile with `df` degrees of freedom.
double t_quantile(double p, double df) {
  return boost::math::quantile(boost::math::students_t(df), p);
}

double z_quantile(double p) {
  return boost::math::quantile(boost::math::normal(), p);
}

/// The sums a ratio of sums (arm a: na / da) and a paired difference of two (a - b) need for
/// their linearized standard errors, in one pass without storing the terms: with z_i =
/// (n_i - R d_i) / mean(d), sum(z^2) = (S_nn - 2 R S_nd + R^2 S_dd) / mean(d)^2.
struct PairSums {
  double na = 0, da = 0, nb = 0, db = 0;
  double nana = 0, nada = 0, dada = 0, nbnb = 0, nbdb = 0, dbdb = 0;
  double nanb = 0, nadb = 0, danb = 0, dadb = 0;
  void add(double a_num, double a_den, double b_num, double b_den) {
    na += a_num;
    da += a_den;
    nb += b_num;
    db += b_den;
    nana += a_num * a_num;
    nada += a_num * a_den;
    dada += a_den * a_den;
    nbnb += b_num * b_num;
    nbdb += b_num * b_den;
    dbdb += b_den * b_den;
    nanb += a_num * b_num;
    nadb += a_num * b_den;
    danb += a_den * b_num;
    dadb += a_den * b_den;
  }
  [[nodiscard]] double ratio_a() const { return ratio(na, da); }
  [[nodiscard]] double ratio_b() const { return ratio(nb, db); }
  /// sum(z_a^2), sum(z_b^2), sum(z_a z_b) for n seeds.
  [[nodiscard]] double zz_a(double n) const {
    const double r = ratio_a(), m = da / n;
    return m > 0 ? std::max(0.0, nana - 2 * r * nada + r * r * dada) / (m * m) : 0.0;
  }
  [[nodiscard]] double zz_b(double n) const {
    const double r = ratio_b(), m = db / n;
    return m > 0 ? std::max(0.0, nbnb - 2 * r * nbdb + r * r * dbdb) / (m * m) : 0.0;
  }
  [[nodiscard]] double zz_ab(double n) const {
    const double ra = ratio_a(), rb = ratio_b(), ma = da / n, mb = db / n;
    if (!(ma > 0) || !(mb > 0)) return 0.0;
    return (nanb - rb * nadb - ra * danb + ra * rb * dadb) / (ma * mb);
  }
  [[nodiscard]] double se_a(std::size_t seeds) const {
    const auto n = static_cast<double>(seeds);
    return seeds < 2 ? 0.0 : std::sqrt(zz_a(n) / (n * (n - 1.0)));
  }
  [[nodiscard]] double se_difference(std::size_t seeds) const {
    const auto n = static_cast<double>(seeds);
    if (seeds < 2) return 0.0;
    const double ss = std::max(0.0, zz_a(n) + zz_b(n) - 2.0 * zz_ab(n));
    return std::sqrt(ss / (n * (n - 1.0)));
  }
};

/// How far a bootstrap-t interval reaches below and above the estimate, in standard errors.
struct TReach {
  double below = 0.0;
  double above = 0.0;
};

/// The bootstrap-t's reach from studentized resamples t* = (estimate* - estimate) / se*
/// (each given by `studentized(indices)`): the span of the symmetric interval (the
/// confidence quantile of |t*|) and the equal-tailed one (the tails' quantiles of t*), each
/// quantile at most twice Student's t(n - 1): a resample without spread whose estimate moved
/// gives an infinite t*, and a sample with one seed far from the rest gives many huge ones.
template <class F>
TReach bootstrap_t_reach(std::size_t n, const BootstrapOptions& o, F&& studentized) {
  core::Rng rng(o.seed);
  std::vector<double> t(static_cast<std::size_t>(o.resamples));
  std::vector<std::size_t> idx(n);
  for (double& v : t) {
    for (std::size_t& i : idx) i = draw_index(rng, n);
    v = studentized(idx);
  }
  const double alpha = 1.0 - o.confidence;
  const double cap = 2.0 * t_quantile(1.0 - 0.5 * alpha, static_cast<double>(n - 1));
  std::sort(t.begin(), t.end());
  const double lower_tail = std::max(-cap, sorted_quantile(t, 0.5 * alpha));
  const double upper_tail = std::min(cap, sorted_quantile(t, 1.0 - 0.5 * alpha));
  for (double& v : t) v = std::abs(v);
  std::sort(t.begin(), t.end());
  const double symmetric = std::min(cap, sorted_quantile(t, o.confidence));
  // estimate - mu = t se: the interval is [estimate - upper se, estimate - lower se].
  return {std::max(symmetric, upper_tail), std::max(symmetric, -lower_tail)};
}

/// (estimate - centre) / se, infinite when se is 0 and the estimate moved.
double signed_t(double estimate, double centre, double se) {
  const double d = estimate - centre;
  if (se > 0.0) return d / se;
  if (d == 0.0) return 0.0;
  return d > 0.0 ? kInf : -kInf;
}

/// A rate's two-sided limits per unit of exposure, and what they rest on.
struct RateLimits {
  double rate = 0.0;
  double lo = 0.0;
  double hi = 0.0;
  double dispersion = 0.0;
  double top_share = 0.0;
  double top = 0.0;
  bool none = true;  ///< no event
};

/// `one_sided_zero`: with no event, the one-sided bound at the confidence; else the two-sided
/// interval's upper end (Garwood's).
RateLimits rate_limits(std::span<const double> events, std::span<const double> exposure,
                       double confidence, bool one_sided_zero) {
  check_confidence(confidence);
  check_lengths(events.size(), exposure.size(), "rate_interval");
  double k = 0.0, m = 0.0, top = 0.0;
  for (std::size_t i = 0; i < events.size(); ++i) {
    if (!(events[i] >= 0.0) || !(exposure[i] >= 0.0) || !std::isfinite(events[i]) ||
        !std::isfinite(exposure[i])) {
      throw std::invalid_argument("rate_interval: events and exposure must be finite and >= 0");
    }
    k += events[i];
    m += exposure[i];
    top = std::max(top, events[i]);
  }
  RateLimits r;
  if (!(m > 0.0)) return r;
  r.rate = k / m;
  if (k == 0.0) {
    r.hi = (one_sided_zero ? poisson_zero_upper_bound(confidence)
                           : poisson_interval(0.0, confidence).hi) /
           m;
    return r;
  }
  r.none = false;
  r.top_share = top / k;
  r.top = top;
  const std::size_t n = events.size();
  double phi = 1.0;
  if (n >= 2) {
    double x2 = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const double mu = r.rate * exposure[i];
      if (mu > 0.0) x2 += (events[i] - mu) * (events[i] - mu) / mu;
    }
    const double p = 0.5 + 0.5 * confidence;
    const double f = t_quantile(p, static_cast<double>(n - 1)) / z_quantile(p);
    phi = std::max(1.0, x2 / static_cast<double>(n - 1)) * f * f;
  }
  const Interval c = poisson_interval(k / phi, confidence);
  r.lo = c.lo * phi / m;
  r.hi = c.hi * phi / m;
  r.dispersion = phi;
  return r;
}

/// The half width of a rate's interval with its seeds scaled by `f` (events and exposure
/// scale with them, the dispersion estimate stays).
double rate_width_scaled(double k, double m, double x2_per_df, double n, double f,
                         double confidence) {
  const double p = 0.5 + 0.5 * confidence;
  const double df = std::max(1.0, n * f - 1.0);
  const double t = t_quantile(p, df) / z_quantile(p);
  const double phi = std::max(1.0, x2_per_df) * t * t;
  return poisson_interval(k * f / phi, confidence).width() * phi / (m * f);
}

/// P(X > Y) of the runs x against the runs y, ties half (x better when higher unless not).
double improvement(std::vector<double> x, std::vector<double> y, bool higher_is_better) {
  if (x.empty() || y.empty()) return 0.5;
  std::sort(y.begin(), y.end());
  double wins = 0.0;
  for (const double v : x) {
    const auto lo = std::lower_bound(y.begin(), y.end(), v);
    const auto hi = std::upper_bound(y.begin(), y.end(), v);
    const auto below = static_cast<double>(lo - y.begin());
    const auto above = static_cast<double>(y.end() - hi);
    const auto ties = static_cast<double>(hi - lo);
    wins += (higher_is_better ? below : above) + 0.5 * ties;
  }
  return wins / (static_cast<double>(x.size()) * static_cast<double>(y.size()));
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

double poisson_zero_upper_bound(double confidence) {
  check_confidence(confidence);
  return -std::log(1.0 - confidence);
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

Interval mean_interval(std::span<const double> num, std::span<const double> den,
                       const BootstrapOptions& o) {
  check_options(o);
  check_lengths(num.size(), den.size(), "mean_interval");
  const std::size_t n = num.size();
  if (n == 0) return {};
  PairSums all;
  for (std::size_t i = 0; i < n; ++i) all.add(num[i], den[i], 0.0, 0.0);
  const double centre = all.ratio_a();
  const double se = all.se_a(n);
  if (n < 2 || !(se > 0.0)) return {centre, centre};
  const TReach reach = bootstrap_t_reach(n, o, [&](const std::vector<std::size_t>& idx) {
    PairSums r;
    for (const std::size_t i : idx) r.add(num[i], den[i], 0.0, 0.0);
    return signed_t(r.ratio_a(), centre, r.se_a(n));
  });
  return {centre - reach.below * se, centre + reach.above * se};
}

RateInterval rate_interval(std::span<const double> events, std::span<const double> exposure,
                           double per, double confidence) {
  const RateLimits r = rate_limits(events, exposure, confidence, true);
  RateInterval out;
  out.ci = {r.lo * per, r.hi * per};
  out.upper_bound_only = r.none;
  out.dispersion = r.dispersion;
  out.top_seed_share = r.top_share;
  out.top_seed_events = r.top;
  return out;
}

Interval median_interval(std::span<const double> values, double confidence) {
  check_confidence(confidence);
  std::vector<double> x(values.begin(), values.end());
  if (x.empty()) return {};
  std::sort(x.begin(), x.end());
  const std::size_t n = x.size();
  // Coverage of [x(k), x(n + 1 - k)]: 1 - 2 P(B <= k - 1), B ~ Binomial(n, 1/2).
  const boost::math::binomial_distribution<double> b(static_cast<double>(n), 0.5);
  std::size_t best = 1;
  for (std::size_t k = 1; 2 * k <= n + 1; ++k) {
    const double cover = 1.0 - 2.0 * boost::math::cdf(b, static_cast<double>(k - 1));
    if (cover + 1e-12 < confidence) break;
    best = k;
  }
  return {x[best - 1], x[n - best]};
}

Interval mean_difference_interval(const PairedRatios& p, const BootstrapOptions& o) {
  check_options(o);
  const std::size_t n = p.num_a.size();
  check_lengths(p.den_a.size(), n, "mean_difference_interval");
  check_lengths(p.num_b.size(), n, "mean_difference_interval");
  check_lengths(p.den_b.size(), n, "mean_difference_interval");
  if (n == 0) return {};
  PairSums all;
  for (std::size_t i = 0; i < n; ++i) all.add(p.num_a[i], p.den_a[i], p.num_b[i], p.den_b[i]);
  const double diff = all.ratio_a() - all.ratio_b();
  const double se = all.se_difference(n);
  if (n < 2 || !(se > 0.0)) return {diff, diff};
  const TReach reach = bootstrap_t_reach(n, o, [&](const std::vector<std::size_t>& idx) {
    PairSums r;
    for (const std::size_t i : idx) r.add(p.num_a[i], p.den_a[i], p.num_b[i], p.den_b[i]);
    return signed_t(r.ratio_a() - r.ratio_b(), diff, r.se_difference(n));
  });
  return {diff - reach.below * se, diff + reach.above * se};
}

double mean_difference_p_value(const PairedRatios& p) {
  const std::size_t n = p.num_a.size();
  check_lengths(p.den_a.size(), n, "mean_difference_p_value");
  check_lengths(p.num_b.size(), n, "mean_difference_p_value");
  check_lengths(p.den_b.size(), n, "mean_difference_p_value");
  if (n < 2) return 1.0;
  PairSums all;
  for (std::size_t i = 0; i < n; ++i) all.add(p.num_a[i], p.den_a[i], p.num_b[i], p.den_b[i]);
  const double se = all.se_difference(n);
  const double diff = all.ratio_a() - all.ratio_b();
  if (!(se > 0.0)) return diff == 0.0 ? 1.0 : 0.0;
  const double t = std::abs(diff) / se;
  return std::min(1.0, 2.0 * boost::math::cdf(boost::math::complement(
                                 boost::math::students_t(static_cast<double>(n - 1)), t)));
}

Interval rate_difference_interval(const PairedRatios& p, double per, double confidence) {
  const std::size_t n = p.num_a.size();
  check_lengths(p.den_a.size(), n, "rate_difference_interval");
  check_lengths(p.num_b.size(), n, "rate_difference_interval");
  check_lengths(p.den_b.size(), n, "rate_difference_interval");
  const RateLimits a = rate_limits(p.num_a, p.den_a, confidence, false);
  const RateLimits b = rate_limits(p.num_b, p.den_b, confidence, false);
  // The seeds' correlation: of each arm's residuals (events minus the rate's share).
  double r = 0.0;
  if (n >= 3 && !a.none && !b.none) {
    std::vector<double> za(n), zb(n);
    for (std::size_t i = 0; i < n; ++i) {
      za[i] = p.num_a[i] - a.rate * p.den_a[i];
      zb[i] = p.num_b[i] - b.rate * p.den_b[i];
    }
    const double ma = sum(za) / static_cast<double>(n), mb = sum(zb) / static_cast<double>(n);
    double sab = 0.0, saa = 0.0, sbb = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      sab += (za[i] - ma) * (zb[i] - mb);
      saa += (za[i] - ma) * (za[i] - ma);
      sbb += (zb[i] - mb) * (zb[i] - mb);
    }
    if (saa > 0.0 && sbb > 0.0) r = std::clamp(sab / std::sqrt(saa * sbb), -1.0, 1.0);
  }
  const double d = a.rate - b.rate;
  const double dl_a = a.rate - a.lo, du_a = a.hi - a.rate;
  const double dl_b = b.rate - b.lo, du_b = b.hi - b.rate;
  const double lower = std::sqrt(std::max(0.0, dl_a * dl_a + du_b * du_b - 2.0 * r * dl_a * du_b));
  const double upper = std::sqrt(std::max(0.0, du_a * du_a + dl_b * dl_b - 2.0 * r * du_a * dl_b));
  return {(d - lower) * per, (d + upper) * per};
}

double rate_difference_p_value(const PairedRatios& p, std::uint64_t seed, int monte_carlo) {
  const std::size_t n = p.num_a.size();
  check_lengths(p.den_a.size(), n, "rate_difference_p_value");
  check_lengths(p.num_b.size(), n, "rate_difference_p_value");
  check_lengths(p.den_b.size(), n, "rate_difference_p_value");
  if (monte_carlo < 1) throw std::invalid_argument("rate_difference_p_value: no draws");
  std::vector<double> d;
  double scale = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!(p.den_a[i] > 0.0) || !(p.den_b[i] > 0.0)) continue;
    const double w = 0.5 * (p.den_a[i] + p.den_b[i]);
    const double v = w * (p.num_a[i] / p.den_a[i] - p.num_b[i] / p.den_b[i]);
    if (v != 0.0) {
      d.push_back(v);
      scale += std::abs(v);
    }
  }
  if (d.empty()) return 1.0;
  const double observed = std::abs(sum(d));
  // Sums in another order round differently: "at least as large" within a hair.
  const double bar = observed - 1e-9 * scale;
  const std::size_t m = d.size();
  if (m <= kExactFlipSeeds) {
    // Every assignment, in Gray-code order: one seed's sign changes from one to the next.
    std::vector<int> sign(m, 1);
    double s = sum(d);
    std::uint64_t at_least = 0;
    const std::uint64_t total = std::uint64_t{1} << m;
    for (std::uint64_t k = 0; k < total; ++k) {
      if (std::abs(s) >= bar) ++at_least;
      if (k + 1 == total) break;
      const auto flip = static_cast<std::size_t>(std::countr_zero(k + 1));
      s -= 2.0 * sign[flip] * d[flip];
      sign[flip] = -sign[flip];
    }
    return static_cast<double>(at_least) / static_cast<double>(total);
  }
  // Monte Carlo, stopped early once kStopExceedances draws were as extreme (Besag and
  // Clifford 1991: then p = h / draws, a valid p-value; a large p needs few draws).
  core::Rng rng(seed);
  std::uint64_t at_least = 0;
  for (int draw = 1; draw <= monte_carlo; ++draw) {
    double s = 0.0;
    std::uint64_t bits = 0;
    for (std::size_t i = 0; i < m; ++i) {
      if (i % 64 == 0) bits = rng.next();
      s += (bits & 1U) ? d[i] : -d[i];
      bits >>= 1U;
    }
    if (std::abs(s) >= bar && ++at_least == kStopExceedances) {
      return static_cast<double>(kStopExceedances) / static_cast<double>(draw);
    }
  }
  return static_cast<double>(at_least + 1) / static_cast<double>(monte_carlo + 1);
}

std::vector<double> holm_adjust(std::span<const double> p_values) {
  const std::size_t m = p_values.size();
  std::vector<std::size_t> order(m);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return p_values[a] < p_values[b]; });
  std::vector<double> out(m, 1.0);
  double running = 0.0;
  for (std::size_t j = 0; j < m; ++j) {
    const double adjusted = std::min(1.0, static_cast<double>(m - j) * p_values[order[j]]);
    running = std::max(running, adjusted);
    out[order[j]] = running;
  }
  return out;
}

Improvement probability_of_improvement(std::span<const double> x, std::span<const double> y,
                                       bool higher_is_better, const BootstrapOptions& o) {
  check_options(o);
  check_lengths(x.size(), y.size(), "probability_of_improvement");
  const std::size_t n = x.size();
  Improvement out;
  if (n == 0) return out;
  out.p = improvement({x.begin(), x.end()}, {y.begin(), y.end()}, higher_is_better);
  out.ci = {out.p, out.p};
  if (n < 2) return out;
  core::Rng rng(o.seed);
  const int resamples = std::min(o.resamples, kImprovementResamples);
  std::vector<double> stats(static_cast<std::size_t>(resamples));
  std::vector<double> xs(n), ys(n);
  for (double& s : stats) {
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = draw_index(rng, n);
      xs[k] = x[i];
      ys[k] = y[i];
    }
    s = improvement(xs, ys, higher_is_better);
  }
  std::sort(stats.begin(), stats.end());
  const double alpha = 1.0 - o.confidence;
  out.ci = {sorted_quantile(stats, 0.5 * alpha), sorted_quantile(stats, 1.0 - 0.5 * alpha)};
  return out;
}

std::size_t seeds_to_halve_mean(std::size_t seeds) {
  if (seeds < 2) return 0;
  const auto half_width = [](double n) { return t_quantile(0.975, n - 1.0) / std::sqrt(n); };
  const double target = 0.5 * half_width(static_cast<double>(seeds));
  std::size_t n = seeds;
  while (half_width(static_cast<double>(n)) > target) ++n;
  return n;
}

std::size_t seeds_to_halve_rate(std::span<const double> events, std::span<const double> exposure,
                                double confidence) {
  check_lengths(events.size(), exposure.size(), "seeds_to_halve_rate");
  const std::size_t n = events.size();
  if (n == 0) return 0;
  const double k = sum(events), m = sum(exposure);
  // No event: the bound goes as 1 / exposure.
  if (!(k > 0.0) || !(m > 0.0) || n < 2) return 2 * n;
  double x2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double mu = k / m * exposure[i];
    if (mu > 0.0) x2 += (events[i] - mu) * (events[i] - mu) / mu;
  }
  const double per_df = x2 / static_cast<double>(n - 1);
  const auto nd = static_cast<double>(n);
  const double target = 0.5 * rate_width_scaled(k, m, per_df, nd, 1.0, confidence);
  const auto width_at = [&](std::size_t seeds) {
    return rate_width_scaled(k, m, per_df, nd, static_cast<double>(seeds) / nd, confidence);
  };
  std::size_t lo = n, hi = 2 * n;
  while (width_at(hi) > target && hi < 1000 * n) hi *= 2;
  while (lo + 1 < hi) {
    const std::size_t mid = lo + (hi - lo) / 2;
    (width_at(mid) > target ? lo : hi) = mid;
  }
  return hi;
}

}  // namespace overtake::eval
