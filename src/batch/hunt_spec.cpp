// `overtake hunt`'s spec checked before anything runs: its flags, its folder and its maps, and
// what makes its shards one hunt.

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>

#include "hunt_internal.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/policies.hpp"
#include "overtake/batch/pool.hpp"
#include "overtake/batch/shard.hpp"
#include "overtake/core/hash.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/scenarios/cut.hpp"

namespace overtake::batch {

using base::check_unique_names;
using base::same_file;
using base::UsageError;
using nlohmann::json;
using planners::PlannerEntry;
using planners::PlannerKind;
using run::Config;
using run::config_hash;
using run::DriveOptions;
using run::load_config;
using run::load_track;
using run::Track;
using run::validate_drive_options;
using scenarios::check_cut_window;

namespace {

constexpr int kMaxFailures = 10000;
/// The largest budget of simulated time (h; some 11 years), and the most runs a hunt takes.
constexpr double kMaxBudgetHours = 100000.0;
constexpr std::size_t kMaxHuntRuns = 100000000;
/// The files a hunt writes into its folder, and the folders whose files it names after the runs
/// (a folder of another's that holds them is not replaced without --force).
constexpr std::array<const char*, 2> kHuntReports = {"hunt.json", "hunt.md"};
constexpr std::array<const char*, 2> kHuntFolders = {"replays", "scenarios"};

}  // namespace

std::size_t hunt_max_runs(const HuntSpec& spec) {
  if (!spec.seeds.empty()) return spec.seeds.size() * spec.maps.size() * spec.traffic.size();
  const double runs = std::floor(spec.budget_hours * 60.0 / spec.minutes + 1e-9);
  // Saturated before the conversion: a budget check_spec refuses gives no wrapped count.
  if (!(runs < static_cast<double>(kMaxHuntRuns))) return kMaxHuntRuns;
  return static_cast<std::size_t>(std::max(1.0, runs));
}

namespace hunt_detail {

void check_spec(const HuntSpec& spec) {
  check_jobs(spec.jobs);
  if (spec.failures < 1 || spec.failures > kMaxFailures) {
    throw UsageError("--failures must be between 1 and " + std::to_string(kMaxFailures));
  }
  if (!(spec.budget_hours > 0.0) || !(spec.budget_hours <= kMaxBudgetHours)) {
    std::ostringstream os;
    os << "--budget-hours must be more than 0 and at most " << kMaxBudgetHours << " (got "
       << spec.budget_hours << ")";
    throw UsageError(os.str());
  }
  if (spec.maps.empty()) throw UsageError("--maps: no map given");
  if (spec.traffic.empty()) throw UsageError("--traffic: no traffic profile given");
  for (std::size_t i = 0; i < spec.maps.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      const auto& a = spec.maps[j];
      const auto& b = spec.maps[i];
      if (a.has_value() == b.has_value() && (!a || same_file(*a, *b))) {
        throw UsageError("--maps: " + map_name(b) + " is named twice (items " +
                         std::to_string(j + 1) + " and " + std::to_string(i + 1) +
                         "); each map is driven once, name it once");
      }
    }
  }
  check_unique_names(spec.traffic, "--traffic");
  check_policy_names({spec.policy}, spec.planners);
  DriveOptions o;  // what every run shares, and each traffic profile
  o.policy = spec.policy;
  o.planners = spec.planners;
  o.minutes = spec.minutes;
  validate_drive_options(o);
  for (const auto& t : spec.traffic) {
    o.traffic = t;
    validate_drive_options(o);
  }
  // Each failure's scenarios are cut as `overtake cut` cuts them: the same bounds, checked now.
  check_cut_window(spec.before_s, spec.after_s);
  const std::size_t runs = hunt_max_runs(spec);
  if (static_cast<double>(runs) >= static_cast<double>(kMaxHuntRuns)) {
    throw UsageError("--budget-hours over --minutes gives more than " +
                     std::to_string(kMaxHuntRuns - 1) +
                     " runs; give a smaller budget or longer runs");
  }
  const std::size_t per_seed = spec.maps.size() * spec.traffic.size();
  const std::uint64_t last_offset = (runs - 1) / per_seed;
  if (spec.seeds.empty() &&
      spec.first_seed > std::numeric_limits<std::uint64_t>::max() - last_offset) {
    throw UsageError("--first-seed: the hunt's seeds go from " + std::to_string(spec.first_seed) +
                     " up " + std::to_string(last_offset) + " more, past the last seed (" +
                     std::to_string(std::numeric_limits<std::uint64_t>::max()) + ")");
  }
  check_shard(spec.shard());
  if (static_cast<std::size_t>(spec.shard_count) > hunt_max_runs(spec)) {
    throw UsageError("--shard: " + std::to_string(spec.shard_count) + " shards of a hunt of " +
                     std::to_string(hunt_max_runs(spec)) +
                     " runs (--budget-hours over --minutes); a shard needs at least one run");
  }
}

json hunt_sweep(const HuntSpec& spec, const Config& config) {
  std::vector<std::string> maps;
  for (const auto& m : spec.maps) maps.push_back(map_name(m));
  json planner = nullptr;
  const PlannerEntry* e = spec.planners ? spec.planners->find(spec.policy) : nullptr;
  if (e && e->kind != PlannerKind::builtin) planner = json::parse(e->describe());
  return {
      {"policy", spec.policy},
      {"planner", planner},
      {"minutes", spec.minutes},
      {"failures", spec.failures},
      {"budget_hours", spec.budget_hours},
      {"find", static_cast<int>(spec.target)},
      {"traffic", spec.traffic},
      {"maps", maps},
      {"first_seed", spec.first_seed},
      {"seeds", spec.seeds},
      {"incident_type",
       spec.incident_type ? json(std::string(sim::to_string(*spec.incident_type))) : json(nullptr)},
      {"before_s", spec.before_s},
      {"warm_up", spec.warm_up_all ? json("all") : json(spec.warm_up_s)},
      {"after_s", spec.after_s},
      {"params_hash", config_hash(config)},
      {"shards", spec.shard_count}};
}

std::vector<std::shared_ptr<const Track>> load_hunt_tracks(const HuntSpec& spec) {
  std::vector<std::shared_ptr<const Track>> tracks;
  for (std::size_t i = 0; i < spec.maps.size(); ++i) {
    tracks.push_back(load_track(spec.maps[i]));
    for (std::size_t j = 0; j < i; ++j) {
      if (tracks[j]->map.content_hash == tracks[i]->map.content_hash) {
        throw UsageError("--maps: " + map_name(spec.maps[i]) + " is the same map as " +
                         map_name(spec.maps[j]) + " (hash " +
                         core::hex64(tracks[i]->map.content_hash) +
                         "); each map is driven once, name it once");
      }
    }
  }
  return tracks;
}

}  // namespace hunt_detail

void check_hunt_out(const std::filesystem::path& out, bool force, const std::string& who,
                    const std::string& remedy) {
  if (force) return;
  std::error_code ec;
  for (const char* name : kHuntReports) {
    const std::filesystem::path file = out / name;
    if (!std::filesystem::exists(std::filesystem::symlink_status(file, ec))) continue;
    throw UsageError(who + file.string() + " exists" +
                     (std::string(name) == "hunt.json" ? " (a hunt's results)" : "") +
                     ": a hunt would replace it; " + remedy);
  }
  for (const char* name : kHuntFolders) {
    const std::filesystem::path dir = out / name;
    if (!std::filesystem::exists(std::filesystem::symlink_status(dir, ec))) continue;
    if (!std::filesystem::is_directory(dir, ec) || !std::filesystem::is_empty(dir, ec)) {
      throw UsageError(who + dir.string() +
                       " is not empty and the folder holds no hunt.json: a hunt would replace "
                       "files in it; " +
                       remedy);
    }
  }
}

void check_hunt_spec(const HuntSpec& spec) {
  hunt_detail::check_spec(spec);
  (void)load_config(spec.config);
  (void)hunt_detail::load_hunt_tracks(spec);
}

}  // namespace overtake::batch
