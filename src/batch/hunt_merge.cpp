// `overtake hunt --merge`: the shards of one hunt joined into its folder: the first failures
// in run order, their groups and scenarios, as one hunt here would have found them.

#include "overtake/batch/hunt.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/merge.hpp"
#include "overtake/batch/shard.hpp"
#include "overtake/core/text_check.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/run/config.hpp"

namespace overtake::batch {

using base::json_text;
using base::read_file;
using base::shell_quote;
using base::UsageError;
using base::write_file_atomic;
using nlohmann::json;
using planners::call_from_description;
using planners::planner_command_line;
using run::kMaxJsonFileBytes;
using run::read_json_file;

namespace {

// One shard's hunt.json, read for merge_hunt.
struct HuntShard {
  std::filesystem::path dir;
  json report;
  std::vector<HuntFailure> failures;
  std::map<std::string, HuntGroup> groups;  ///< by situation
};

HuntShard read_hunt_shard(const std::filesystem::path& dir) {
  HuntShard h;
  h.dir = dir;
  const std::filesystem::path file = dir / "hunt.json";
  try {
    h.report = read_json_file(file);
    for (const json& f : h.report.at("failures")) {
      HuntFailure x;
      x.run = f.at("run").get<std::size_t>();
      x.seed = f.at("seed").get<std::uint64_t>();
      x.traffic = f.at("traffic").get<std::string>();
      x.map = f.at("map").get<std::string>();
      x.t_s = f.at("t_s").get<double>();
      x.what = f.at("what").get<std::string>();
      x.situation = f.at("situation").get<std::string>();
      x.replay = f.at("replay").get<std::string>();
      x.rerun = f.at("rerun").get<std::string>();
      h.failures.push_back(std::move(x));
    }
    for (const json& g : h.report.at("groups")) {
      HuntGroup x;
      x.situation = g.at("situation").get<std::string>();
      x.reactive = g.at("reactive").get<std::string>();
      x.replayed = g.at("replayed").get<std::string>();
      x.cut_error = g.at("cut_error").get<std::string>();
      if (g.contains("reproduces")) {
        x.reproduces_reactive = g.at("reproduces").at("reactive").get<std::string>();
        x.reproduces_replayed = g.at("reproduces").at("replayed").get<std::string>();
        x.reproduced = g.at("reproduced").get<bool>();
        if (g.contains("warm_up") && g.at("warm_up").is_string())
          x.warm_up = g.at("warm_up").get<std::string>();
        if (g.at("nondeterministic").is_string())
          x.nondeterministic = g.at("nondeterministic").get<std::string>();
      }
      h.groups.emplace(x.situation, std::move(x));
    }
    const json& shard = h.report.at("shard");
    (void)shard.at("sweep");
    (void)shard.at("revision").get<std::string>();
    (void)shard.at("index").get<int>();
    (void)shard.at("count").get<int>();
    (void)shard.at("finished").get<bool>();
    (void)shard.at("max_runs").get<std::size_t>();
  } catch (const std::exception& e) {
    throw UsageError("merge: " + file.string() + " is not the report of a hunt shard (" + e.what() +
                     "); run each shard with hunt --shard I/N");
  }
  return h;
}

// Copies `rel` of `from` to the same place under `to` (the merge's replays and scenarios).
void copy_into(const std::filesystem::path& from, const std::filesystem::path& to,
               const std::string& rel) {
  if (rel.empty()) return;
  std::error_code ec;
  const std::filesystem::path dest = to / rel;
  std::filesystem::create_directories(dest.parent_path(), ec);
  if (!std::filesystem::copy_file(from / rel, dest,
                                  std::filesystem::copy_options::overwrite_existing, ec) ||
      ec) {
    throw std::runtime_error(dest.string() + ": cannot copy " + (from / rel).string() + " here (" +
                             ec.message() + ")");
  }
}

// Copies a cut scenario of a shard (`rel` of `from`) into `to`, naming the replay it was cut
// from where the merge put that replay: the merged folder stands alone.
void copy_scenario(const std::filesystem::path& from, const std::filesystem::path& to,
                   const std::string& rel) {
  if (rel.empty()) return;
  nlohmann::ordered_json j;
  try {
    const std::string text = read_file(from / rel, kMaxJsonFileBytes);
    core::require_json_depth(text, (from / rel).string());
    j = nlohmann::ordered_json::parse(text);
  } catch (const std::exception& e) {  // unreadable, too deep, or not JSON
    throw UsageError("merge: " + (from / rel).string() + " is not a scenario (" + e.what() + ")");
  }
  if (j.contains("cut") && j["cut"].contains("from") && j["cut"]["from"].contains("replay")) {
    const std::filesystem::path replay = j["cut"]["from"]["replay"].get<std::string>();
    j["cut"]["from"]["replay"] = (to / "replays" / replay.filename()).string();
  }
  std::error_code ec;
  std::filesystem::create_directories((to / rel).parent_path(), ec);
  write_file_atomic(to / rel, json_text(j, 2) + "\n");
}

}  // namespace

namespace {

MergeKind hunt_merge_kind() {
  MergeKind k;
  k.noun = "hunt";
  k.other_sweep = "is a shard of another hunt than";
  k.sweep_fields = "(policy, minutes, failures, budget, traffic, maps, seeds or parameters differ)";
  k.results_files = {"hunt.json"};
  k.holds_results = "a hunt";
  k.check_out = [](const std::filesystem::path& out) {
    check_hunt_out(out, false, "merge: --out: ", "move it away, or merge into a new folder");
  };
  return k;
}

MergePart merge_part(const HuntShard& h) {
  const json& sh = h.report["shard"];
  MergePart p;
  p.dir = h.dir;
  p.sweep = sh["sweep"];
  p.revision = sh["revision"].get<std::string>();
  p.shard = {sh["index"].get<int>(), sh["count"].get<int>()};
  p.finished = sh["finished"].get<bool>();
  return p;
}

// A failure found, and the shard it came from.
struct Found {
  const HuntShard* from;
  const HuntFailure* failure;
};

// The first `failures` failures of the shards in run order (a shard keeps a run's failures in
// order): what one hunt would have found.
std::vector<Found> first_failures(const std::vector<HuntShard>& shards, std::size_t wanted) {
  std::vector<Found> all;
  for (const HuntShard& h : shards) {
    for (const HuntFailure& f : h.failures) all.push_back({&h, &f});
  }
  std::stable_sort(all.begin(), all.end(),
                   [](const Found& a, const Found& b) { return a.failure->run < b.failure->run; });
  if (all.size() > wanted) all.resize(wanted);
  return all;
}

// Adds a failure to the merged outcome, with its replay, and its group (with its scenarios)
// when it begins one.
void add_merged_failure(HuntOutcome& o, std::map<std::string, std::size_t>& group_of,
                        const Found& f, const json& sweep, const std::filesystem::path& out) {
  copy_into(f.from->dir, out, f.failure->replay);
  const std::size_t index = o.failures.size();
  o.failures.push_back(*f.failure);
  auto [it, is_new] = group_of.emplace(f.failure->situation, o.groups.size());
  if (is_new) {
    // The shard's group of this situation began with this failure: none came before it.
    const auto g = f.from->groups.find(f.failure->situation);
    if (g == f.from->groups.end()) {
      throw UsageError("merge: " + f.from->dir.string() + "/hunt.json lists a failure in '" +
                       f.failure->situation + "' but no group of it");
    }
    HuntGroup group = g->second;
    group.failures.clear();
    copy_scenario(f.from->dir, out, group.reactive);
    copy_scenario(f.from->dir, out, group.replayed);
    const std::string policy = sweep["policy"].get<std::string>();
    group.repro =
        group.reactive.empty()
            ? f.failure->rerun
            : planner_command_line(call_from_description(policy, sweep.value("planner", json()))) +
                  " --scenario " + shell_quote((out / group.reactive).string());
    o.groups.push_back(std::move(group));
  }
  o.groups[it->second].failures.push_back(index);
}

}  // namespace

HuntOutcome merge_hunt(const std::vector<std::filesystem::path>& dirs,
                       const std::filesystem::path& out) {
  if (dirs.empty()) throw UsageError("merge: name the hunt folders to join");
  std::vector<HuntShard> shards;
  std::vector<MergePart> parts;
  for (const auto& dir : dirs) {
    shards.push_back(read_hunt_shard(dir));
    parts.push_back(merge_part(shards.back()));
  }
  check_merge(parts, out, hunt_merge_kind());
  const json& first = shards.front().report["shard"];
  const json sweep = first["sweep"];
  const auto wanted = sweep["failures"].get<std::size_t>();
  const std::vector<Found> all = first_failures(shards, wanted);
  // The runs one hunt would have taken: up to the run of the last failure it kept, or all.
  const std::size_t last_run =
      all.size() == wanted ? all.back().failure->run : first["max_runs"].get<std::size_t>() - 1;
  HuntOutcome o;
  for (const HuntShard& h : shards) {
    for (const json& r : h.report["shard"]["run_seconds"]) {
      if (r[0].get<std::size_t>() > last_run) continue;
      ++o.runs;
      o.simulated_s += r[1].get<double>();
    }
    o.wall_s = std::max(o.wall_s, h.report["timing"].value("wall_s", 0.0));
  }
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) {
    throw std::runtime_error(out.string() + ": cannot create the output folder (" + ec.message() +
                             ")");
  }
  std::map<std::string, std::size_t> group_of;
  for (const Found& f : all) add_merged_failure(o, group_of, f, sweep, out);
  HuntSpec spec;
  spec.policy = sweep["policy"].get<std::string>();
  spec.minutes = sweep["minutes"].get<double>();
  write_file_atomic(out / "hunt.json", json_text(hunt_json(spec, o), 2) + "\n");
  write_file_atomic(out / "hunt.md", hunt_markdown(spec, o));
  return o;
}

}  // namespace overtake::batch
