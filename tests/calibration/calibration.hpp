#pragma once
// The evaluation's calibration on benches shaped like real ones: populations of real bench
// rows (tests/data/calibration/bench_rows.csv: 100 seeds of every policy and traffic profile,
// 30- and 10-minute runs, and a "twin" of each 30-minute run by a planner nudged by 1e-5),
// synthetic benches drawn from them (seeds drawn with replacement), and what the intervals and
// the verdicts do on those: coverage of the true (population) figure, false alarms of
// `compare --fail-if-worse` on benches equal in distribution, power against a real change.
// Used by the calibration tests and by the program that prints docs/evaluation.md's tables.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "overtake/core/random.hpp"
#include "overtake/eval/compare.hpp"
#include "overtake/eval/metrics.hpp"

namespace overtake::eval::calibration {

/// One policy's runs in one traffic profile, one per seed, in seed order.
struct Population {
  std::string set;  ///< "a30" (30-minute runs), "b30" (their twins), "a10" (10-minute runs)
  std::string policy;
  std::string traffic;
  std::vector<std::uint64_t> seed;
  std::vector<double> miles, hours, incidents, collisions, at_fault, near_misses;
  [[nodiscard]] std::size_t size() const { return seed.size(); }
  [[nodiscard]] std::string name() const { return set + " " + policy + " / " + traffic; }
};

/// Keyed by (set, policy, traffic).
using Populations = std::map<std::tuple<std::string, std::string, std::string>, Population>;

/// Reads the CSV; throws std::runtime_error naming the line on anything malformed.
[[nodiscard]] Populations load(const std::filesystem::path& csv);
/// The calibration rows kept in the tree.
[[nodiscard]] const Populations& rows();
/// A population; throws when there is none.
[[nodiscard]] const Population& population(const std::string& set, const std::string& policy,
                                           const std::string& traffic);

/// The rate figures (counts per 100 miles).
enum class Rate : std::uint8_t { incidents, collisions, at_fault, near_misses };
inline constexpr Rate kRates[] = {Rate::incidents, Rate::collisions, Rate::at_fault,
                                  Rate::near_misses};
[[nodiscard]] const char* name(Rate r);
[[nodiscard]] const std::vector<double>& counts(const Population& p, Rate r);
/// The population's figure: miles over hours; 100 x events over miles.
[[nodiscard]] double true_speed(const Population& p);
[[nodiscard]] double true_rate(const Population& p, Rate r);
/// The share of the population's events that its top 5% of seeds hold.
[[nodiscard]] double top_share(const Population& p, Rate r);
/// The per-seed counts' variance over their mean (1 for Poisson counts).
[[nodiscard]] double dispersion(const Population& p, Rate r);

/// Seeds drawn with replacement (indices into a population).
[[nodiscard]] std::vector<std::size_t> draw(core::Rng& rng, std::size_t population, std::size_t n);

/// Coverage over `draws` synthetic benches of n seeds: the share of intervals that hold the
/// population's figure (a paired one: the difference of the two populations' figures, a and b
/// paired by seed index).
[[nodiscard]] double speed_coverage(const Population& p, std::size_t n, int draws,
                                    std::uint64_t seed, int resamples);
[[nodiscard]] double rate_coverage(const Population& p, Rate r, std::size_t n, int draws,
                                   std::uint64_t seed);
[[nodiscard]] double speed_difference_coverage(const Population& a, const Population& b,
                                               std::size_t n, int draws, std::uint64_t seed,
                                               int resamples);
[[nodiscard]] double rate_difference_coverage(const Population& a, const Population& b, Rate r,
                                              std::size_t n, int draws, std::uint64_t seed);

/// A run row from a population's run `i`, labelled with `seed` (speed raised by `add_mph` and
/// the distance scaled by `mile_scale`, for a real change or noise).
[[nodiscard]] RunRow run_row(const Population& p, std::size_t i, std::uint64_t seed,
                             double add_mph = 0.0, double mile_scale = 1.0);

/// A bench of runs for compare_benches (manifest: one map, 30 minutes).
[[nodiscard]] BenchData bench(const std::string& name, std::vector<RunRow> runs);

/// What `compare --fail-if-worse` did over many draws of a pair of benches.
struct GateOutcome {
  int draws = 0;
  int failed = 0;    ///< some figure "worse" (exit status 1)
  int withheld = 0;  ///< too few seeds (exit status 2)
  int better = 0;    ///< draws in which `watched` was "better"
  [[nodiscard]] double failure_rate() const { return draws ? double(failed) / draws : 0.0; }
  [[nodiscard]] double better_rate() const { return draws ? double(better) / draws : 0.0; }
};

/// Runs compare_benches on `draws` pairs of benches made by `make` (base, candidate) and
/// counts its outcomes; `watched` ("policy / traffic: metric") is the figure whose "better"
/// verdicts are counted (power).
[[nodiscard]] GateOutcome gate(
    int draws, std::uint64_t seed,
    const std::function<std::pair<BenchData, BenchData>(core::Rng&)>& make,
    const std::string& watched = "", int resamples = 200);

/// Benches of one policy over both profiles, n seeds: base from `a`, candidate from `b` (per
/// profile), paired by seed index (`paired`: each seed's two runs to the arms in a random
/// order) or on independent seeds; the candidate's speed raised by `add_mph`.
[[nodiscard]] std::function<std::pair<BenchData, BenchData>(core::Rng&)> policy_benches(
    const std::string& set_a, const std::string& set_b, const std::string& policy, std::size_t n,
    bool paired, double add_mph = 0.0);

/// Benches of one policy over both profiles on independent seeds, the candidate's events of
/// `r` thinned (each kept with probability `keep`: its true rate times `keep`).
[[nodiscard]] std::function<std::pair<BenchData, BenchData>(core::Rng&)> thinned_benches(
    const std::string& set, const std::string& policy, std::size_t n, Rate r, double keep);

/// The construction that once failed the gate 23% of the time: the first `n` seeds of every
/// 30-minute policy and profile, each row's distance scaled by independent noise of `sd` (relative)
/// in both benches.
[[nodiscard]] std::function<std::pair<BenchData, BenchData>(core::Rng&)> noisy_benches(
    std::size_t n, double sd);

}  // namespace overtake::eval::calibration
