#pragma once
// What the files of `overtake bench` share (batch/bench*.cpp): a bench's identity across its
// shards, and the files its runs are summarised into.

#include <filesystem>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/batch/bench.hpp"

namespace overtake::batch::bench_detail {

/// What makes shards one sweep: the bench's manifest without its shard (nor its build).
[[nodiscard]] nlohmann::json sweep_identity(nlohmann::json manifest);

/// Writes runs.jsonl and the summaries (CSV, JSON, Markdown) of `runs` into `out`, and sets
/// the outcome's summary and runs done.
void write_outputs(const std::filesystem::path& out, const std::vector<nlohmann::json>& runs,
                   const nlohmann::json& manifest, BenchOutcome& outcome);

}  // namespace overtake::batch::bench_detail
