// A bench's rows as they are read back (`compare`, `bench --resume`, `bench merge`): runs.jsonl
// read line by line and each row checked against the bench's manifest. Nothing here drives:
// the fuzz harness `bench_folder` links it alone.

#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/core/text_check.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"

namespace overtake::batch {

using base::json_text;
using base::read_file;
using base::UsageError;
namespace {

using nlohmann::json;

/// Lines of a runs.jsonl listed in one message at most; the rest are counted.
constexpr std::size_t kMaxLinesListed = 10;

// nlohmann's message without its "[json.exception.parse_error.101] " prefix, and without the
// line in it (each line of runs.jsonl is parsed alone: it would always say line 1).
std::string json_error_text(const json::exception& e) {
  std::string text = e.what();
  const auto close = text.find("] ");
  if (text.rfind("[json.exception.", 0) == 0 && close != std::string::npos)
    text.erase(0, close + 2);
  const auto at = text.find("at line 1, ");
  if (at != std::string::npos) text.erase(at + 3, 8);  // "at line 1, column 5": "at column 5"
  return text;
}

// What a bench's manifest (bench.json) says its rows must be.
struct ManifestSweep {
  std::vector<BenchCombo> all;
  Shard shard;
  std::optional<std::string> map_hash, params_hash, revision;
  std::optional<double> minutes;
};

ManifestSweep sweep_of(const json& manifest) {
  ManifestSweep m;
  BenchSpec spec;
  spec.policies = manifest.at("policies").get<std::vector<std::string>>();
  spec.traffic = manifest.at("traffic").get<std::vector<std::string>>();
  // Whole numbers that fit, or the manifest is refused: a seed of 2.8e76 is read as a double,
  // and converting it to an integer would be undefined (found by the bench_folder harness).
  if (!manifest.at("seeds").is_array()) throw std::invalid_argument("its seeds are not a list");
  for (const json& seed : manifest.at("seeds")) {
    if (!seed.is_number_unsigned()) {
      throw std::invalid_argument("a seed is " + json_text(seed) +
                                  ", not a whole number from 0 to " +
                                  std::to_string(std::numeric_limits<std::uint64_t>::max()));
    }
    spec.seeds.push_back(seed.get<std::uint64_t>());
  }
  m.all = bench_combinations(spec);
  if (manifest.contains("shard")) {
    m.shard = parse_shard(manifest["shard"].get<std::string>());
  }
  if (manifest.contains("combinations") &&
      (!manifest["combinations"].is_number_unsigned() ||
       manifest["combinations"].get<std::size_t>() != m.all.size())) {
    throw std::invalid_argument("its combinations (" + json_text(manifest["combinations"]) +
                                ") are not its policies x traffic x seeds (" +
                                std::to_string(m.all.size()) + ")");
  }
  const auto text_at = [&](const json::json_pointer& at) -> std::optional<std::string> {
    if (!manifest.contains(at)) return std::nullopt;
    return manifest[at].get<std::string>();
  };
  m.map_hash = text_at(json::json_pointer("/map/hash"));
  m.params_hash = text_at(json::json_pointer("/params_hash"));
  m.revision = text_at(json::json_pointer("/git_revision"));
  if (manifest.contains("minutes")) m.minutes = manifest["minutes"].get<double>();
  return m;
}

// A row's text field at `at`, when it has one.
std::optional<std::string> row_text(const json& row, const json::json_pointer& at) {
  if (!row.contains(at) || !row[at].is_string()) return std::nullopt;
  return row[at].get<std::string>();
}

}  // namespace

BenchRowsFile read_bench_rows(const std::filesystem::path& file, bool allow_cut_off_end) {
  BenchRowsFile out;
  std::error_code ec;
  if (!std::filesystem::exists(std::filesystem::symlink_status(file, ec))) {
    return out;  // no run finished yet
  }
  // A regular file of a bounded size: /dev/zero as runs.jsonl would be one endless line.
  const std::string text = read_file(file);
  std::vector<std::string> bad;
  std::size_t bad_count = 0;
  std::size_t n = 0;
  for (std::size_t from = 0; from < text.size();) {
    ++n;
    const std::size_t end = text.find('\n', from);
    const bool whole_line = end != std::string::npos;  // it ended with its newline
    const std::string_view line =
        std::string_view(text).substr(from, whole_line ? end - from : std::string::npos);
    from = whole_line ? end + 1 : text.size();
    if (line.empty()) continue;
    std::string why;
    try {
      json j;
      if (const auto at = core::json_too_deep_at(line)) {
        why = "nested deeper than " + std::to_string(core::kMaxJsonDepth) + " levels (at byte " +
              std::to_string(*at) + ")";
      } else if (j = json::parse(line); !j.is_object()) {
        why = "not a JSON object";
      } else if (!j.contains("index") || !j["index"].is_number_unsigned()) {
        why = "no run number (\"index\")";
      } else {
        out.rows.push_back({std::move(j), n});
        continue;
      }
    } catch (const json::exception& e) {
      why = json_error_text(e);
    }
    if (!whole_line) {  // the last line, without its newline: a write a kill cut off
      if (allow_cut_off_end) {
        out.cut_off_line = n;
        continue;
      }
      why +=
          "; the line is cut off (the bench was killed while writing it): `overtake bench "
          "--resume` with the bench's flags drives that run again";
    }
    if (++bad_count <= kMaxLinesListed) {
      bad.push_back(file.string() + ":" + std::to_string(n) + ": not a run (" + why + ")");
    }
  }
  if (bad_count > 0) {
    std::string message;
    for (const std::string& b : bad) message += (message.empty() ? "" : "; ") + b;
    if (bad_count > bad.size()) {
      message += "; and " + std::to_string(bad_count - bad.size()) + " more lines like them";
    }
    throw UsageError(message);
  }
  return out;
}

namespace {

// How a row's run was driven otherwise than the bench's (another map, length or parameters),
// or empty.
std::string driven_otherwise(const json& cfg, const ManifestSweep& sweep) {
  const auto map_hash = row_text(cfg, json::json_pointer("/map/hash"));
  if (map_hash && sweep.map_hash && *map_hash != *sweep.map_hash) {
    return " was driven on another map (" +
           row_text(cfg, json::json_pointer("/map/path")).value_or("?") + ", hash " + *map_hash +
           "; this bench's map has hash " + *sweep.map_hash + ")";
  }
  if (cfg.contains("minutes") && cfg["minutes"].is_number() && sweep.minutes &&
      cfg["minutes"].get<double>() != *sweep.minutes) {
    return " lasted another length (" + json_text(cfg["minutes"]) +
           " minutes; this bench's runs last " + json_text(json(*sweep.minutes)) + ")";
  }
  const auto params = row_text(cfg, json::json_pointer("/params_hash"));
  if (params && sweep.params_hash && *params != *sweep.params_hash) {
    return " ran with other parameters (hash " + *params + "; this bench's: " + *sweep.params_hash +
           ")";
  }
  return {};
}

}  // namespace

void check_bench_rows(const std::vector<BenchRow>& rows, const json& manifest,
                      const std::filesystem::path& file, std::optional<BenchBuild>& build,
                      const std::string& who, const std::string& hint) {
  const std::filesystem::path manifest_path = file.parent_path() / kBenchManifestFile;
  ManifestSweep sweep;
  try {
    sweep = sweep_of(manifest);
  } catch (const std::exception& e) {
    throw UsageError(who + manifest_path.string() + " is not a bench's manifest (" + e.what() +
                     ")" + hint);
  }
  const auto different_builds = [&](const std::string& revision, const std::string& where) {
    throw UsageError(who + "the runs come from different builds of overtake: " + build->revision +
                     " (" + build->where + ") and " + revision + " (" + where +
                     "); a bench's runs come from one build, which may drive differently from "
                     "another" +
                     hint);
  };
  if (sweep.revision) {
    if (!build) {
      build = BenchBuild{*sweep.revision, "in " + manifest_path.string()};
    } else if (*sweep.revision != build->revision) {
      different_builds(*sweep.revision, "in " + manifest_path.string());
    }
  }
  const auto combo_text = [](const BenchCombo& c) {
    return c.policy + " / " + c.traffic + " / seed " + std::to_string(c.seed);
  };
  std::map<std::size_t, std::size_t> line_of;             // run -> its line
  std::map<std::string, std::size_t> run_of_combination;  // policy, traffic, seed -> run
  for (const BenchRow& r : rows) {
    const auto idx = r.run["index"].get<std::size_t>();
    const std::string at = file.string() + ":" + std::to_string(r.line) + ": ";
    const auto bad = [&](const std::string& why) { throw UsageError(who + at + why + hint); };
    const std::string run = "run " + std::to_string(idx);
    if (idx >= sweep.all.size()) {
      bad(run + " is not one of this bench's " + std::to_string(sweep.all.size()) + " runs");
    }
    if (!sweep.shard.holds(idx)) {
      bad(run + " belongs to another shard than this folder's (" + sweep.shard.text() + ")");
    }
    const BenchCombo& c = sweep.all[idx];
    const json& cfg = r.run.contains("config") ? r.run["config"] : json();
    const bool same = cfg.is_object() && cfg.value("policy", "") == c.policy &&
                      cfg.value("traffic", "") == c.traffic && cfg.contains("seed") &&
                      cfg["seed"].is_number_unsigned() &&
                      cfg["seed"].get<std::uint64_t>() == c.seed;
    if (!same)
      bad("the row of " + run + " is not " + combo_text(c) + " (got " + json_text(cfg) + ")");
    if (const auto [it, first] = line_of.emplace(idx, r.line); !first) {
      bad(run + " appears twice (" + combo_text(c) + ", lines " + std::to_string(it->second) +
          " and " + std::to_string(r.line) + "); a run counts once");
    }
    const std::string key = c.policy + "\n" + c.traffic + "\n" + std::to_string(c.seed);
    if (const auto [it, first] = run_of_combination.emplace(key, idx); !first) {
      bad(run + " is " + combo_text(c) + " again (as run " + std::to_string(it->second) +
          "); a run counts once");
    }
    if (const std::string why = driven_otherwise(cfg, sweep); !why.empty()) bad(run + why);
    if (const auto rev = row_text(r.run, json::json_pointer("/provenance/git_revision"))) {
      if (!build) {
        build = BenchBuild{*rev, "in " + file.string() + ":" + std::to_string(r.line)};
      } else if (*rev != build->revision) {
        different_builds(*rev, "in " + file.string() + ":" + std::to_string(r.line) + ", " + run);
      }
    }
  }
}

std::vector<BenchCombo> bench_combinations(const BenchSpec& spec) {
  const double runs = static_cast<double>(spec.policies.size()) *
                      static_cast<double>(spec.traffic.size()) *
                      static_cast<double>(spec.seeds.size());
  if (runs > static_cast<double>(kMaxBenchRuns)) {
    throw UsageError("policies x traffic x seeds make more than " + std::to_string(kMaxBenchRuns) +
                     " runs; split the bench (--seeds) into several");
  }
  std::vector<BenchCombo> out;
  out.reserve(static_cast<std::size_t>(runs));
  for (const auto& p : spec.policies) {
    for (const auto& t : spec.traffic) {
      for (const auto s : spec.seeds) out.push_back({out.size(), p, t, s});
    }
  }
  return out;
}

}  // namespace overtake::batch
