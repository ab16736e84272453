#pragma once
// A bench's summary, pure functions over its run rows: per policy and traffic profile the
// figures with their 95% intervals (bootstrap over runs for mean speed and incident-free
// miles, exact Poisson for every rate), collisions by kind and at fault, near misses, and how
// many seeds would halve each interval; paired comparisons of every two policies on the same
// seeds; and the comparison of two benches (before and after a change). As JSON (the report
// page's data, summary.json), CSV and Markdown. docs/evaluation.md says what each figure is.

#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/eval/metrics.hpp"

namespace overtake::eval {

/// One row per policy and traffic profile that has runs, in the order of `policies` x
/// `traffic` (then any other pair found in the runs, in order of appearance). `runs` should
/// come in sweep order: the figures are the same for any order, but sums of doubles keep their
/// last bits only in one.
[[nodiscard]] nlohmann::json summarize(const std::vector<RunRow>& runs,
                                       const std::vector<std::string>& policies,
                                       const std::vector<std::string>& traffic);

/// Paired comparison of two sets of runs matched by seed (runs without a partner are left
/// out): for each metric, candidate minus base with its bootstrap interval over the seeds,
/// the probability of improvement and a verdict ("better", "worse", "no difference": the
/// interval excludes 0 or not). `key` names the comparison (it seeds the bootstraps). A metric
/// that some run cannot give (an older row) is null.
[[nodiscard]] nlohmann::json compare_paired(const std::vector<const RunRow*>& base,
                                            const std::vector<const RunRow*>& candidate,
                                            std::string_view key,
                                            const std::vector<Metric>& metrics);

/// Every two policies on each traffic profile, on the seeds both ran: {"traffic", "policy",
/// "versus", "seeds", "figures"} with policy as the candidate (differences are policy minus
/// versus).
[[nodiscard]] nlohmann::json pair_policies(const std::vector<RunRow>& runs,
                                           const std::vector<std::string>& policies,
                                           const std::vector<std::string>& traffic);

[[nodiscard]] std::string summary_csv(const nlohmann::json& rows);
[[nodiscard]] std::string pairs_csv(const nlohmann::json& pairs);
/// The tables of summary.md: speed and incidents, near misses, collisions by kind, comfort and
/// the planner, paired comparisons, and how many seeds would halve each interval.
[[nodiscard]] std::string summary_markdown(const nlohmann::json& rows, const nlohmann::json& pairs);

/// A number with `decimals` decimals ("%.*f").
[[nodiscard]] std::string fixed(double v, int decimals);
/// A signed difference ("+0.27", "-1.20").
[[nodiscard]] std::string signed_fixed(double v, int decimals);

}  // namespace overtake::eval
