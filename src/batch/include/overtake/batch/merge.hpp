#pragma once
// What `bench merge` and `hunt merge` check alike before they join the folders of shards:
// the output is none of them and holds no results, the shards are of one sweep and one build,
// each shard is there once and finished, and none is missing.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/batch/shard.hpp"

namespace overtake::batch {

/// One folder a merge joins, as its report or manifest says.
struct MergePart {
  std::filesystem::path dir;
  nlohmann::json sweep;  ///< what makes shards one sweep (flags, map, parameters)
  std::string revision;  ///< the build that ran it ("": not recorded, not compared)
  Shard shard;
  bool finished = true;
};

/// The words and checks of one kind of merge.
struct MergeKind {
  std::string noun;                        ///< "bench", "hunt"
  std::string other_sweep;                 ///< "comes from a different bench configuration than"
  std::string sweep_fields;                ///< "(policies, traffic, ... differ)"
  std::vector<std::string> results_files;  ///< in `out`: it holds results already
  std::string holds_results;               ///< "bench results", "a hunt"
  /// The kind's own check of `out` (files of its names that no merge wrote).
  std::function<void(const std::filesystem::path& out)> check_out;
};

/// Throws UsageError starting with "merge: " when the parts cannot be joined into `out`:
/// `out` is one of them or holds results, a part is of another sweep or build, a shard is
/// doubled, unfinished or missing.
void check_merge(const std::vector<MergePart>& parts, const std::filesystem::path& out,
                 const MergeKind& kind);

}  // namespace overtake::batch
