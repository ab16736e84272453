// `overtake compare A B`: two bench folders' paired comparison, or two risk estimates' ratio,
// printed and written, with its exit status.

#include <filesystem>
#include <iostream>
#include <set>

#include <nlohmann/json.hpp>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/batch/risk.hpp"
#include "overtake/eval/compare.hpp"

namespace overtake::batch {

using base::json_text;
using base::kExitFailure;
using base::kExitOk;
using base::kExitUsage;
using base::same_file;
using base::UsageError;
using base::write_file_atomic;

int compare_folders(const CompareRequest& r) {
  eval::CompareOptions o;
  std::set<std::string> seen;
  for (const auto& p : r.pairs) {
    o.pairs.push_back(parse_policy_pair(p));
    if (!seen.insert(o.pairs.back().base + "=" + o.pairs.back().candidate).second) {
      throw UsageError("--pair: '" + p + "' is given twice");
    }
  }
  if (!r.figures.empty()) o.metrics = parse_metric_list(r.figures);
  // The comparison never takes the place of a bench's own files.
  for (const std::filesystem::path& dir : {r.before, r.after}) {
    for (const char* name : kBenchFiles) {
      const std::filesystem::path file = dir / name;
      if (!r.json.empty() && same_file(r.json, file)) {
        throw UsageError("--json: " + r.json.string() + " is " + file.string() +
                         ", a file of a bench being compared; write it elsewhere");
      }
    }
  }
  // Two risk estimates compare as a ratio of rates.
  const bool risk_a = holds_risk(r.before), risk_b = holds_risk(r.after);
  if (risk_a != risk_b) {
    throw UsageError(
        "one folder holds a risk estimate (risk.json) and the other not: "
        "compare two benches, or two risk estimates");
  }
  if (risk_a) {
    const nlohmann::json result = compare_risk_folders(r.before, r.after);
    if (!r.json.empty()) write_file_atomic(r.json, json_text(result, 2) + "\n");
    if (!r.quiet) std::cout << compare_risk_text(result);
    if (r.fail_if_worse && result["verdict"] == "higher") return kExitFailure;
    return kExitOk;
  }
  const nlohmann::json result = compare_bench_folders(r.before, r.after, o);
  if (!r.json.empty()) write_file_atomic(r.json, json_text(result, 2) + "\n");
  if (!r.quiet) std::cout << eval::compare_text(result);
  if (!r.fail_if_worse) return kExitOk;
  if (!result["worse"].empty()) return kExitFailure;
  if (!result["withheld"].empty()) {
    for (const auto& w : result["withheld"]) {
      std::cerr << "overtake compare: no verdict, " << w.get<std::string>() << "\n";
    }
    return kExitUsage;
  }
  return kExitOk;
}

}  // namespace overtake::batch
