#include "overtake/batch/merge.hpp"

#include <set>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"

namespace overtake::batch {
namespace {

using base::UsageError;

void check_part(const MergePart& part, const MergePart& first, const std::filesystem::path& out,
                const MergeKind& kind) {
  if (base::same_file(part.dir, out)) {
    throw UsageError("merge: --out " + out.string() + " is one of the folders being joined (" +
                     part.dir.string() + "); its results would be rewritten: merge into a new " +
                     "folder");
  }
  if (part.sweep != first.sweep) {
    throw UsageError("merge: " + part.dir.string() + " " + kind.other_sweep + " " +
                     first.dir.string() + " " + kind.sweep_fields);
  }
  if (!part.revision.empty() && !first.revision.empty() && part.revision != first.revision) {
    throw UsageError("merge: the shards come from different builds of overtake: " + first.revision +
                     " (in " + first.dir.string() + ") and " + part.revision + " (in " +
                     part.dir.string() + "); run every shard with the same binary");
  }
  if (part.shard.count != first.shard.count) {
    throw UsageError("merge: " + part.dir.string() + " is shard " + part.shard.text() + " and " +
                     first.dir.string() + " shard " + first.shard.text() + ": shards of one " +
                     kind.noun + " are of one count");
  }
  if (!part.finished) {
    throw UsageError("merge: " + part.dir.string() + " holds an unfinished shard (shard " +
                     std::to_string(part.shard.index) + " was interrupted); run it again");
  }
}

}  // namespace

void check_merge(const std::vector<MergePart>& parts, const std::filesystem::path& out,
                 const MergeKind& kind) {
  if (parts.empty()) throw UsageError("merge: name the " + kind.noun + " folders to join");
  const MergePart& first = parts.front();
  std::set<int> seen;
  for (const MergePart& part : parts) {
    check_part(part, first, out, kind);
    if (!seen.insert(part.shard.index).second) {
      throw UsageError("merge: shard " + std::to_string(part.shard.index) + " of " +
                       std::to_string(part.shard.count) + " appears twice (" + part.dir.string() +
                       ")");
    }
  }
  if (static_cast<int>(seen.size()) != first.shard.count) {
    throw UsageError("merge: the folders hold " + std::to_string(seen.size()) + " of the " +
                     kind.noun + "'s " + std::to_string(first.shard.count) +
                     " shards; a shard is missing");
  }
  for (const std::string& name : kind.results_files) {
    if (std::filesystem::exists(out / name)) {
      throw UsageError("merge: --out " + out.string() + " already holds " + kind.holds_results +
                       "; merge into a new folder");
    }
  }
  if (kind.check_out) kind.check_out(out);
}

}  // namespace overtake::batch
