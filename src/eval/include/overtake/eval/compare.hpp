#pragma once
// Two benches compared (before and after a change to a planner): policies matched by name or
// paired by hand, their runs paired by traffic profile and seed, every figure's change with
// its 95% interval, and whether it is beyond noise. Pure functions over the benches' rows.

#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/eval/metrics.hpp"
#include "overtake/eval/stats.hpp"

namespace overtake::eval {

/// Two benches whose runs cannot be pairs (another map, other minutes or latency, nothing in
/// common).
class NotComparable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A bench as compared: a name for messages (its folder), what was run (bench.json) and its
/// runs in sweep order.
struct BenchData {
  std::string name;
  nlohmann::json manifest;
  std::vector<RunRow> runs;
};

/// A policy of the base bench compared with one of the candidate bench.
struct PolicyPair {
  std::string base;
  std::string candidate;
  friend bool operator==(const PolicyPair&, const PolicyPair&) = default;
};

/// What to compare.
struct CompareOptions {
  /// Empty: every policy that both benches ran, by name.
  std::vector<PolicyPair> pairs;
  /// Empty: every metric.
  std::vector<Metric> metrics;
  /// Bootstrap resamples of each interval (the verdicts' tests do not resample; fewer make a
  /// many-draw calibration affordable).
  int resamples = kBootstrapResamples;
};

/// Compares `candidate` with `base`. Throws NotComparable when their runs cannot be pairs
/// (another map, other minutes or latency, no policy, profile and seed in common) and
/// std::invalid_argument when a pair names a policy a bench did not run. The result: {"base",
/// "candidate", "notes", "comparisons": [{"base_policy", "candidate_policy", "traffic", "seeds",
/// "figures"}], "verdicts" (the method: verdict_method), "worse": ["policy / traffic: metric",
/// ...], "withheld": ["policy / traffic: too few seeds: ...", ...]} with figures as
/// compare_paired gives them (candidate minus base), their verdicts judged as one family.
[[nodiscard]] nlohmann::json compare_benches(const BenchData& base, const BenchData& candidate,
                                             const CompareOptions& options);

/// The comparison as text for a terminal: a table per compared policy and profile, then the
/// verdict.
[[nodiscard]] std::string compare_text(const nlohmann::json& result);

}  // namespace overtake::eval
