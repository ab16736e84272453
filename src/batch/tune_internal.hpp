#pragma once
// What the files of `overtake tune` share (batch/tune*.cpp): the maps of a search, and the
// risk of a trial and of the validation (tune_risk.cpp).

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/batch/risk.hpp"
#include "overtake/batch/tune.hpp"

namespace overtake::batch::tune_detail {

/// A map of the search: a file, or nullopt for the built-in track.
using MapChoice = std::optional<std::filesystem::path>;

/// The maps a trial drives: those named, or the built-in track.
[[nodiscard]] std::vector<MapChoice> maps_of(const TuneSpec& spec);
[[nodiscard]] std::string map_label(const MapChoice& map);

/// The constraints a trial is judged by: --constraint's, and --max-risk's on risk_per_100mi.
[[nodiscard]] std::vector<TuneConstraint> constraints_of(const TuneSpec& spec);

/// Refuses a risk the search cannot estimate (UsageError naming the flag): bad numbers, runs
/// shorter than risk takes, risk figures named with no risk estimated, the validation's risk
/// runs on a training seed or the trials' on a held-out one.
void check_tune_risk(const TuneSpec& spec);

/// The planner a trial (or a validation) estimates the risk of: its policy, catalog and
/// config as its bench runs it. The rest of the RiskSpec is filled by the functions below.
struct RiskPlanner {
  std::string policy;
  std::shared_ptr<const planners::PlannerCatalog> planners;
  std::optional<std::filesystem::path> config;
};

/// A trial's risk: an estimate on each map and traffic profile of the search (TuneRisk::hours
/// each, the trials' runs), into `dir` (dir/MAP-TRAFFIC/ for each), pooled into the figures
/// of tune_risk_figure_names. A planner that fails in a run gives null figures and
/// "risk_error" (the trial is then not feasible). nullopt: interrupted.
[[nodiscard]] std::optional<nlohmann::json> trial_risk(const TuneSpec& spec,
                                                       const RiskPlanner& planner,
                                                       const std::filesystem::path& dir,
                                                       const std::atomic<bool>* stop);

/// The validation's risk on one map: the start's and the best's estimates on the held-out
/// runs (TuneRisk::validation_hours each, every traffic profile), into dir/risk-start and
/// dir/risk-best, with their ratio (eval::rate_ratio). Null when interrupted (and
/// `interrupted` set).
[[nodiscard]] nlohmann::json validate_risk_on(const TuneSpec& spec, const RiskPlanner& start,
                                              const RiskPlanner& best, const MapChoice& map,
                                              const std::filesystem::path& dir,
                                              const std::atomic<bool>* stop, bool& interrupted);

/// In a sentence: whether the best is within --max-risk on the held-out runs (its estimate and
/// its interval's upper end), and how its rate compares with the start's.
[[nodiscard]] std::string risk_verdict_of(const TuneSpec& spec, const nlohmann::json& validation);

}  // namespace overtake::batch::tune_detail
