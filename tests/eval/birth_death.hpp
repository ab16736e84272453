#pragma once
// A birth-death chain on 0..top whose event is reaching `top` (it then starts again at 0):
// a system splitting can run whose rate per step is known exactly, from the chain's
// stationary distribution. The score is the state; one step is one unit of exposure and cost.

#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "overtake/core/random.hpp"
#include "overtake/eval/splitting.hpp"

namespace overtake::eval::testing {

struct BirthDeath {
  int top = 20;
  double up = 0.3;    ///< P(x -> x + 1)
  double down = 0.5;  ///< P(x -> x - 1) for x > 0
  long steps = 2000;  ///< per base run

  /// The exact event rate per step: pi(top - 1) * up.
  [[nodiscard]] double exact_rate() const { return stationary()[top - 1] * up; }

  /// The stationary distribution of the chain with the step into `top` sent to 0, solved by
  /// Gaussian elimination. A run starts from it, so that its expected count is exactly
  /// steps * exact_rate() (no start-up transient).
  [[nodiscard]] std::vector<double> stationary() const {
    const int n = top;  // states 0..top-1
    std::vector<std::vector<double>> a(n, std::vector<double>(n + 1, 0.0));
    // pi P = pi, i.e. sum_i pi_i (P_ij - delta_ij) = 0; the last equation replaced by sum = 1.
    for (int i = 0; i < n; ++i) {
      const double d = i > 0 ? down : 0.0;
      const double stay = 1.0 - up - d;
      auto add = [&](int j, double p) { a[j][i] += p; };
      add(i, stay);
      if (i > 0) add(i - 1, d);
      add(i + 1 < n ? i + 1 : 0, up);
      a[i][i] -= 1.0;
    }
    for (int i = 0; i < n; ++i) a[n - 1][i] = 1.0;
    a[n - 1][n] = 1.0;
    for (int c = 0; c < n; ++c) {
      int piv = c;
      for (int r = c + 1; r < n; ++r)
        if (std::abs(a[r][c]) > std::abs(a[piv][c])) piv = r;
      std::swap(a[c], a[piv]);
      for (int r = 0; r < n; ++r) {
        if (r == c) continue;
        const double f = a[r][c] / a[c][c];
        for (int k = c; k <= n; ++k) a[r][k] -= f * a[c][k];
      }
    }
    std::vector<double> pi(n);
    for (int i = 0; i < n; ++i) pi[i] = a[i][n] / a[i][i];
    return pi;
  }
};

class BirthDeathSystem final : public SplitSystem {
 public:
  BirthDeathSystem(const BirthDeath& chain, std::uint64_t seed) : chain_(chain), rng_(seed) {
    const std::vector<double> pi = chain.stationary();
    double u = rng_.uniform01();
    for (x_ = 0; x_ + 1 < chain.top && u >= pi[x_]; ++x_) u -= pi[x_];
  }
  double score() override { return x_; }
  std::size_t save() override {
    saved_[next_] = {x_, t_, rng_};
    return next_++;
  }
  void restore(std::size_t handle, std::optional<std::uint64_t> reseed) override {
    const Saved& s = saved_.at(handle);
    x_ = s.x;
    t_ = s.t;
    rng_ = reseed ? core::Rng(*reseed) : s.rng;
  }
  void release(std::size_t handle) override { saved_.erase(handle); }
  SplitStep advance() override {
    SplitStep s;
    const double u = rng_.uniform01();
    if (u < chain_.up) {
      ++x_;
    } else if (x_ > 0 && u < chain_.up + chain_.down) {
      --x_;
    }
    if (x_ == chain_.top) {
      s.events = 1;
      x_ = 0;
    }
    ++t_;
    s.score = x_;
    s.exposure = 1.0;
    s.cost = 1.0;
    s.ended = t_ >= chain_.steps;
    return s;
  }

 private:
  struct Saved {
    int x;
    long t;
    core::Rng rng;
  };
  BirthDeath chain_;
  core::Rng rng_;
  int x_ = 0;
  long t_ = 0;
  std::map<std::size_t, Saved> saved_;
  std::size_t next_ = 0;
};

/// Levels every `spacing` states below the top, each splitting `split` ways.
inline SplitLevels chain_levels(const BirthDeath& chain, int spacing, int split) {
  SplitLevels l;
  for (int x = spacing; x < chain.top; x += spacing) {
    l.thresholds.push_back(x);
    l.splits.push_back(split);
  }
  return l;
}

/// One estimate from `runs` base runs, their seeds from `seed`.
struct ChainEstimate {
  SplitEstimate estimate;
  double cost = 0.0;
};
inline ChainEstimate estimate_chain(const BirthDeath& chain, const SplitLevels& levels, int runs,
                                    std::uint64_t seed) {
  std::vector<double> y, m;
  ChainEstimate out;
  for (int r = 0; r < runs; ++r) {
    const std::uint64_t s = core::derive_seed(seed, static_cast<std::uint64_t>(r));
    BirthDeathSystem sys(chain, s);
    const SplitTally t = run_split(sys, levels, {.max_paths = 1000000, .seed = s ^ 0x5bd1e995});
    y.push_back(t.weighted_events);
    m.push_back(t.exposure);
    out.cost += t.cost;
  }
  out.estimate = split_estimate(y, m);
  return out;
}

}  // namespace overtake::eval::testing
