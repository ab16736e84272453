// `overtake bench merge`: the folders of one bench's shards joined into --out (their rows, the
// replays they recorded, the summaries and the page), the same as one unsharded bench.
#include <algorithm>
#include <filesystem>
#include <set>
#include <string>
#include <vector>
#include "overtake/base/build_info.hpp"

#include <nlohmann/json.hpp>

#include "bench_internal.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/batch/bench_page.hpp"
#include "overtake/batch/merge.hpp"
#include "overtake/run/config.hpp"

namespace overtake::batch {

using base::json_text;
using base::UsageError;
using base::write_file_atomic;
using bench_detail::sweep_identity;
using nlohmann::json;
using run::read_json_file;

namespace {
constexpr const char* kRunsFile = kBenchRunsFile;
constexpr const char* kManifestFile = kBenchManifestFile;
}  // namespace
using bench_detail::write_outputs;

namespace {

// Copies the shards' recorded replays (replays/*.otr) into out/replays/, as an unsharded
// bench would hold them (each run is in one shard only, so the names do not clash). Returns
// the replays now in out/replays/ that came from the shards, in name order.
std::vector<std::filesystem::path> merge_replays(const std::vector<std::filesystem::path>& dirs,
                                                 const std::filesystem::path& out) {
  namespace fs = std::filesystem;
  const fs::path to = out / kReplaysFolder;
  std::set<fs::path> merged;
  std::error_code ec;
  for (const auto& dir : dirs) {
    const fs::path from = dir / kReplaysFolder;
    if (!fs::is_directory(from, ec)) continue;
    std::set<fs::path> otrs;  // in name order: the same copies whatever the listing order
    for (const auto& entry : fs::directory_iterator(from)) {
      if (entry.path().extension() == ".otr" && entry.is_regular_file(ec))
        otrs.insert(entry.path());
    }
    for (const fs::path& otr : otrs) {
      const fs::path dest = to / otr.filename();
      merged.insert(dest);
      if (fs::equivalent(otr, dest, ec)) continue;  // merging into one of the shards
      fs::create_directories(to, ec);
      if (!fs::copy_file(otr, dest, fs::copy_options::overwrite_existing, ec) || ec) {
        throw std::runtime_error(dest.string() + ": cannot copy the replay " + otr.string() +
                                 " here (" + ec.message() + ")");
      }
    }
  }
  return {merged.begin(), merged.end()};
}

}  // namespace

namespace {

// A shard's bench.json, read for merge_bench.
json read_merge_manifest(const std::filesystem::path& dir) {
  json m;
  try {
    m = read_json_file(dir / kManifestFile);
  } catch (const std::exception& e) {
    throw UsageError("merge: " + (dir / kManifestFile).string() + " is missing or unreadable (" +
                     e.what() + ")");
  }
  if (!m.is_object()) {
    throw UsageError("merge: " + (dir / kManifestFile).string() +
                     " is not a bench's manifest (not a JSON object)");
  }
  return m;
}

// What merge_check sees of a shard: its sweep, build and shard, from its manifest.
MergePart merge_part(const std::filesystem::path& dir, const json& manifest) {
  MergePart p;
  p.dir = dir;
  p.sweep = sweep_identity(manifest);
  const auto rev = manifest.find("git_revision");
  if (rev != manifest.end() && rev->is_string()) p.revision = rev->get<std::string>();
  const auto shard = manifest.find("shard");
  try {
    if (shard != manifest.end()) p.shard = parse_shard(shard->get<std::string>());
  } catch (const std::exception& e) {
    throw UsageError("merge: " + (dir / kManifestFile).string() + ": its shard is not I/N (" +
                     e.what() + ")");
  }
  return p;
}

MergeKind bench_merge_kind() {
  MergeKind k;
  k.noun = "bench";
  k.other_sweep = "comes from a different bench configuration than";
  k.sweep_fields = "(policies, traffic, seeds, minutes, map or parameters differ)";
  k.results_files = {kRunsFile, kManifestFile};
  k.holds_results = "bench results";
  k.check_out = [](const std::filesystem::path& out) {
    check_bench_out(out, false, "merge: --out: ", "move it away, or merge into a new folder");
  };
  return k;
}

// The rows of every shard, each checked as --resume checks them (its run, once, on the
// sweep's map, length, parameters and build); `build` is the one build across every shard's.
std::vector<json> merged_rows(const std::vector<std::filesystem::path>& dirs,
                              const std::vector<json>& manifests,
                              std::optional<BenchBuild>& build) {
  std::vector<json> runs;
  std::map<std::size_t, std::filesystem::path> seen;  // run -> the folder holding it
  for (std::size_t d = 0; d < dirs.size(); ++d) {
    const std::filesystem::path file = dirs[d] / kRunsFile;
    BenchRowsFile rows;
    try {
      rows = read_bench_rows(file, false);
    } catch (const UsageError& e) {
      throw UsageError("merge: " + std::string(e.what()));
    }
    check_bench_rows(rows.rows, manifests[d], file, build,
                     "merge: ", "; run every shard of a bench with the same binary and flags");
    for (BenchRow& r : rows.rows) {
      const auto idx = r.run["index"].get<std::size_t>();
      if (const auto [it, first] = seen.emplace(idx, dirs[d]); !first) {
        throw UsageError("merge: run " + std::to_string(idx) + " appears twice (in " +
                         it->second.string() + " and " + dirs[d].string() + ")");
      }
      runs.push_back(std::move(r.run));
    }
  }
  return runs;
}

}  // namespace

BenchOutcome merge_bench(const std::vector<std::filesystem::path>& dirs,
                         const std::filesystem::path& out) {
  if (dirs.empty()) throw UsageError("merge: name the bench output folders to join");
  std::vector<json> manifests;
  std::vector<MergePart> parts;
  for (const auto& dir : dirs) {
    manifests.push_back(read_merge_manifest(dir));
    parts.push_back(merge_part(dir, manifests.back()));
  }
  check_merge(parts, out, bench_merge_kind());
  std::optional<BenchBuild> build;
  std::vector<json> runs = merged_rows(dirs, manifests, build);
  json manifest = manifests.front();
  if (build) manifest["git_revision"] = build->revision;
  const auto total = manifest["combinations"].get<std::size_t>();
  if (runs.size() != total) {
    throw UsageError("merge: the folders hold " + std::to_string(runs.size()) + " of the sweep's " +
                     std::to_string(total) + " runs; a shard is missing or unfinished");
  }
  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec)
    throw std::runtime_error(out.string() + ": cannot create the output folder (" + ec.message() +
                             ")");
  manifest["shard"] = "1/1";
  write_file_atomic(out / kManifestFile, json_text(manifest, 2) + "\n");
  BenchOutcome outcome;
  write_outputs(out, runs, manifest, outcome);
  outcome.replays = merge_replays(dirs, out);
  return outcome;
}

}  // namespace overtake::batch
