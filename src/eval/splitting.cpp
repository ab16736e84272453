#include "overtake/eval/splitting.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>

#include "overtake/core/random.hpp"

namespace overtake::eval {

void SplitLevels::validate() const {
  if (thresholds.size() != splits.size()) {
    throw std::invalid_argument("levels: " + std::to_string(thresholds.size()) +
                                " thresholds but " + std::to_string(splits.size()) + " splits");
  }
  for (std::size_t j = 0; j < thresholds.size(); ++j) {
    if (!std::isfinite(thresholds[j]))
      throw std::invalid_argument("levels: a threshold is not finite");
    if (j > 0 && !(thresholds[j] > thresholds[j - 1])) {
      throw std::invalid_argument("levels: thresholds must increase (threshold " +
                                  std::to_string(j + 1) + " is not above the one before)");
    }
    if (splits[j] < 1 || splits[j] > 1000) {
      throw std::invalid_argument("levels: splits must be 1 to 1000 (got " +
                                  std::to_string(splits[j]) + ")");
    }
  }
}

int SplitLevels::level_of(double score) const {
  const auto it = std::upper_bound(thresholds.begin(), thresholds.end(), score);
  return static_cast<int>(it - thresholds.begin());
}

namespace {

// The depth-first walk of one base run's tree of paths: a path runs until it ends or falls
// below the level it was made at; at each up-crossing it makes its copies and runs each to
// its end before it goes on itself.
class SplitWalk {
 public:
  SplitWalk(SplitSystem& system, const SplitLevels& levels, const SplitLimits& limits,
            SplitTally& tally)
      : sys_(system), levels_(levels), limits_(limits), tally_(tally) {
    weight_.assign(levels.thresholds.size() + 1, 1.0);
    for (std::size_t j = 0; j < levels.thresholds.size(); ++j) {
      weight_[j + 1] = weight_[j] / levels.splits[j];
    }
    tally_.crossings.assign(levels.thresholds.size(), 0.0);
  }

  void run_base() { run_path(0, 0, 0, levels_.level_of(sys_.score())); }

 private:
  // Runs path `id`, made at level `birth`, now at `level` and to cross up to `pending`.
  void run_path(std::size_t id, int birth, int level, int pending) {
    const bool base = id == 0;
    for (;;) {
      while (level < pending) level = cross(level, pending);
      const SplitStep s = sys_.advance();
      tally_.cost += s.cost;
      if (base) {
        tally_.exposure += s.exposure;
        tally_.base_cost += s.cost;
        tally_.base_events += s.events;
      }
      for (int e = 0; e < s.events; ++e) {
        tally_.events.push_back({weight_[level], level, id, base_cost_at_branch(base), s.at});
        tally_.weighted_events += weight_[level];
      }
      if (s.ended) return;
      const int now = levels_.level_of(s.score);
      if (now < birth) return;  // a copy that fell back below where it was made
      pending = now;
      level = std::min(level, now);
    }
  }

  // The path at `level` goes up through the next threshold: its copies are made and run;
  // returns the level it is at then.
  int cross(int level, int pending) {
    tally_.crossings[level] += weight_[level];
    const int split = levels_.splits[level];
    const int up = level + 1;
    if (split <= 1) return up;
    const std::size_t handle = sys_.save();
    if (depth_++ == 0) branch_cost_ = tally_.base_cost;
    for (int r = 1; r < split; ++r) {
      const std::size_t id = tally_.paths++;
      if (tally_.paths > limits_.max_paths) {
        throw SplitExplosion("one base run made more than " + std::to_string(limits_.max_paths) +
                             " paths: the splits are too many for the score (lower them)");
      }
      sys_.restore(handle, core::derive_seed(limits_.seed, id));
      run_path(id, up, up, pending);
    }
    --depth_;
    sys_.restore(handle, std::nullopt);
    sys_.release(handle);
    return up;
  }

  [[nodiscard]] double base_cost_at_branch(bool base) const {
    return base ? tally_.base_cost : branch_cost_;
  }

  SplitSystem& sys_;
  const SplitLevels& levels_;
  const SplitLimits& limits_;
  SplitTally& tally_;
  std::vector<double> weight_;  // by level: 1 / (R_1 ... R_k)
  int depth_ = 0;
  double branch_cost_ = 0.0;  // the base path's cost when the outermost branch was made
};

}  // namespace

SplitTally run_split(SplitSystem& system, const SplitLevels& levels, const SplitLimits& limits) {
  levels.validate();
  SplitTally tally;
  SplitWalk walk(system, levels, limits, tally);
  walk.run_base();
  return tally;
}

SplitEstimate split_estimate(std::span<const double> weighted_events,
                             std::span<const double> exposure, double confidence) {
  if (weighted_events.size() != exposure.size()) {
    throw std::invalid_argument("split estimate: unequal lengths");
  }
  if (!(confidence > 0.0 && confidence < 1.0)) {
    throw std::invalid_argument("split estimate: confidence must be between 0 and 1");
  }
  SplitEstimate e;
  e.runs = weighted_events.size();
  double y = 0.0, m = 0.0;
  for (std::size_t i = 0; i < e.runs; ++i) {
    if (!(weighted_events[i] >= 0.0) || !(exposure[i] >= 0.0) ||
        !std::isfinite(weighted_events[i]) || !std::isfinite(exposure[i])) {
      throw std::invalid_argument(
          "split estimate: a run's events or exposure is negative or "
          "not finite");
    }
    y += weighted_events[i];
    m += exposure[i];
    if (weighted_events[i] > 0.0) ++e.runs_with_events;
  }
  if (m <= 0.0) return e;
  if (y <= 0.0) {
    e.upper_bound_only = true;
    e.ci = {0.0, -std::log(1.0 - confidence) / m};
    return e;
  }
  e.rate = y / m;
  const auto n = static_cast<double>(e.runs);
  if (e.runs < 2) {
    // One run says nothing of its own spread: as Poisson.
    e.effective_events = y;
  } else {
    double ss = 0.0;
    for (std::size_t i = 0; i < e.runs; ++i) {
      const double z = weighted_events[i] - e.rate * exposure[i];
      ss += z * z;
    }
    e.variance = ss / (m * m) * n / (n - 1.0);
    e.effective_events = e.variance > 0.0 ? e.rate * e.rate / e.variance : y;
  }
  const double p = 0.5 + 0.5 * confidence;
  double f = 1.0;
  if (e.runs >= 2) {
    f = boost::math::quantile(boost::math::students_t(n - 1.0), p) /
        boost::math::quantile(boost::math::normal(), p);
  }
  const double k = e.effective_events / (f * f);
  const Interval c = poisson_interval(k, confidence);
  e.ci = {c.lo * e.rate / k, c.hi * e.rate / k};
  if (e.runs < 2) e.variance = e.rate / m;
  return e;
}

RateRatio rate_ratio(const RateEstimate& base, const RateEstimate& candidate) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  RateRatio r;
  const bool b0 = base.upper_bound_only || base.rate <= 0.0;
  const bool c0 = candidate.upper_bound_only || candidate.rate <= 0.0;
  if (b0 && c0) {
    r.defined = false;
    r.ci = {0.0, kInf};
    r.verdict = "no verdict";
    return r;
  }
  if (b0) {
    r.defined = false;
    r.ci = {base.ci.hi > 0.0 ? candidate.ci.lo / base.ci.hi : 0.0, kInf};
  } else if (c0) {
    r.ratio = 0.0;
    r.ci = {0.0, base.ci.lo > 0.0 ? candidate.ci.hi / base.ci.lo : kInf};
  } else {
    const double lb = std::log(base.rate), lc = std::log(candidate.rate);
    const auto log_of = [](double x) { return x > 0.0 ? std::log(x) : -kInf; };
    const double lr = lc - lb;
    const double down = std::hypot(lc - log_of(candidate.ci.lo), log_of(base.ci.hi) - lb);
    const double up = std::hypot(log_of(candidate.ci.hi) - lc, lb - log_of(base.ci.lo));
    r.ratio = std::exp(lr);
    r.ci = {std::exp(lr - down), std::exp(lr + up)};
  }
  if (r.ci.lo > 1.0) {
    r.verdict = "higher";
  } else if (r.ci.hi < 1.0) {
    r.verdict = "lower";
  } else {
    r.verdict = "no difference";
  }
  return r;
}

}  // namespace overtake::eval
