// The app's edge of overtake::eval: a bench's rows summarized for its output files and its
// report page, bench folders read for `overtake compare` (and the Python module), and the
// compare flags parsed. The figures themselves are eval's.

#include <algorithm>
#include <sstream>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/eval/summary.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"

namespace overtake::batch {

using base::json_text;
using base::UsageError;
using run::read_json_file;

using nlohmann::json;

BenchSummary summarize_bench(std::vector<json> runs, const std::vector<std::string>& policies,
                             const std::vector<std::string>& traffic, const std::string& where) {
  // Sweep order, whatever order the runs finished in: the figures' sums keep their last bits
  // and the bootstraps draw the same runs.
  std::stable_sort(runs.begin(), runs.end(), [](const json& a, const json& b) {
    const auto index = [](const json& r) {
      return r.contains("index") && r["index"].is_number_unsigned() ? r["index"].get<std::size_t>()
                                                                    : 0;
    };
    return index(a) < index(b);
  });
  std::vector<eval::RunRow> rows;
  rows.reserve(runs.size());
  for (const json& r : runs) {
    const std::string at =
        where + ", run " +
        (r.contains("index") ? json_text(r["index"]) : std::to_string(rows.size()));
    try {
      rows.push_back(eval::read_run_row(r, at));
    } catch (const std::invalid_argument& e) {
      throw UsageError(e.what());
    }
  }
  return {eval::summarize(rows, policies, traffic), eval::pair_policies(rows, policies, traffic)};
}

eval::BenchData load_bench_for_compare(const std::filesystem::path& dir,
                                       std::vector<std::string>& notes) {
  eval::BenchData b;
  b.name = dir.string();
  const auto manifest_path = dir / kBenchManifestFile;
  const auto runs_path = dir / kBenchRunsFile;
  if (!std::filesystem::is_directory(dir)) {
    throw std::runtime_error(dir.string() +
                             ": no such folder (give two `overtake bench --out` folders, or two "
                             "`overtake risk --out` folders)");
  }
  try {
    b.manifest = read_json_file(manifest_path);
  } catch (const std::exception& e) {
    throw std::runtime_error(manifest_path.string() + " is missing or unreadable (" + e.what() +
                             "): not a bench output folder");
  }
  if (!b.manifest.is_object()) {
    throw std::runtime_error(manifest_path.string() +
                             " is not a bench manifest (not a JSON object)");
  }
  if (!std::filesystem::exists(runs_path)) {
    throw std::runtime_error(runs_path.string() + " is missing: the bench has no finished run");
  }
  // Rows it cannot vouch for are refused, naming them: a line that is not a run, a run written
  // twice, a run of another sweep, map, length or build.
  std::vector<json> runs;
  try {
    BenchRowsFile file = read_bench_rows(runs_path, false);
    std::optional<BenchBuild> build;
    check_bench_rows(file.rows, b.manifest, runs_path, build, "", "");
    for (BenchRow& r : file.rows) runs.push_back(std::move(r.run));
  } catch (const UsageError& e) {
    throw std::runtime_error(e.what());
  }
  std::stable_sort(runs.begin(), runs.end(), [](const json& x, const json& y) {
    return x["index"].get<std::size_t>() < y["index"].get<std::size_t>();
  });
  for (const json& r : runs) {
    try {
      b.runs.push_back(
          eval::read_run_row(r, runs_path.string() + ", run " + json_text(r["index"])));
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(e.what());
    }
  }
  if (b.runs.empty()) throw std::runtime_error(runs_path.string() + " holds no finished run");
  const json& combinations =
      b.manifest.contains("combinations") ? b.manifest["combinations"] : json();
  const std::size_t total =
      combinations.is_number_unsigned() ? combinations.get<std::size_t>() : std::size_t{0};
  if (total > b.runs.size() && b.manifest.value("shard", std::string("1/1")) == "1/1") {
    notes.push_back(dir.string() + " is unfinished: " + std::to_string(b.runs.size()) + " of " +
                    std::to_string(total) + " runs");
  }
  return b;
}

eval::PolicyPair parse_policy_pair(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size() ||
      text.find('=', eq + 1) != std::string::npos) {
    throw UsageError("--pair: '" + text +
                     "' is not OLD=NEW (a policy of the first bench = one of the second)");
  }
  return {text.substr(0, eq), text.substr(eq + 1)};
}

std::vector<eval::Metric> parse_metric_list(const std::string& text) {
  std::vector<eval::Metric> out;
  std::stringstream ss(text);
  std::string name;
  while (std::getline(ss, name, ',')) {
    if (name.empty()) continue;
    const auto m = eval::parse_metric(name);
    if (!m) {
      std::string known;
      for (const eval::Metric k : eval::all_metrics()) {
        known += (known.empty() ? "" : ", ") + std::string(eval::info(k).name);
      }
      throw UsageError("--figures: unknown figure '" + name + "' (known: " + known + ")");
    }
    if (std::find(out.begin(), out.end(), *m) == out.end()) out.push_back(*m);
  }
  if (out.empty()) throw UsageError("--figures: no figure given");
  return out;
}

nlohmann::json compare_bench_folders(const std::filesystem::path& base,
                                     const std::filesystem::path& candidate,
                                     const eval::CompareOptions& options) {
  std::vector<std::string> notes;
  const eval::BenchData a = load_bench_for_compare(base, notes);
  const eval::BenchData b = load_bench_for_compare(candidate, notes);
  nlohmann::json result;
  try {
    result = eval::compare_benches(a, b, options);
  } catch (const eval::NotComparable& e) {
    throw std::runtime_error(e.what());
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--pair: ") + e.what());
  }
  for (auto it = notes.rbegin(); it != notes.rend(); ++it) {
    result["notes"].insert(result["notes"].begin(), *it);
  }
  return result;
}

}  // namespace overtake::batch
