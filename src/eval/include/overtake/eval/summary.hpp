#pragma once
// A bench's summary, pure functions over its run rows: per policy and traffic profile the
// figures with their 95% intervals over the seeds (stats.hpp: bootstrap-t for mean speed,
// order statistics for the median incident-free miles, overdispersed exact intervals for every
// rate), collisions as contacts by kind and at fault, near misses, and how many seeds would
// halve each interval; paired comparisons of every two policies on the same seeds, with
// verdicts corrected for the family of tests; and the comparison of two benches (before and
// after a change). As JSON (the report page's data, summary.json), CSV and Markdown.
// docs/evaluation.md says what each figure is.

#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/eval/metrics.hpp"
#include "overtake/eval/stats.hpp"

namespace overtake::eval {

/// One row per policy and traffic profile that has runs, in the order of `policies` x
/// `traffic` (then any other pair found in the runs, in order of appearance). `runs` should
/// come in sweep order: the figures are the same for any order, but sums of doubles keep their
/// last bits only in one.
[[nodiscard]] nlohmann::json summarize(const std::vector<RunRow>& runs,
                                       const std::vector<std::string>& policies,
                                       const std::vector<std::string>& traffic);

/// Paired comparison of two sets of runs matched by seed (runs without a partner are left
/// out): for each metric, candidate minus base with its 95% interval over the seeds, the
/// p-value of its test, the probability of improvement with its interval. `verdict` is "too
/// few seeds" below kMinSeeds pairs (then no interval, test or probability), else null until
/// judge_family decides it over the family the comparison belongs to. `key` names the
/// comparison (it seeds the bootstraps). A metric that some run cannot give (an older row) is
/// null.
[[nodiscard]] nlohmann::json compare_paired(const std::vector<const RunRow*>& base,
                                            const std::vector<const RunRow*>& candidate,
                                            std::string_view key,
                                            const std::vector<Metric>& metrics,
                                            int resamples = kBootstrapResamples);

/// The verdicts of a family of comparisons (each {"figures": {metric: figure}}): Holm's
/// correction over every figure tested, `p_adjusted`, and "better" or "worse" (by the figure's
/// direction) when the adjusted p-value is below kFamilyAlpha, else "no difference". Returns
/// the family's size (tests).
std::size_t judge_family(nlohmann::json& comparisons);

/// How the verdicts of a family of `tests` tests were reached (summary.json's "verdicts").
[[nodiscard]] nlohmann::json verdict_method(std::size_t tests);
/// The tests a family of comparisons holds.
[[nodiscard]] std::size_t family_size(const nlohmann::json& comparisons);

/// Every two policies on each traffic profile, on the seeds both ran: {"traffic", "policy",
/// "versus", "seeds", "figures"} with policy as the candidate (differences are policy minus
/// versus); every figure of every pair and profile one family.
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
