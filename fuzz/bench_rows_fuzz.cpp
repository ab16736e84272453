// Bench rows (runs.jsonl, read by `overtake compare`, `bench --resume`, `bench merge` and the
// report page): each line parsed as JSON and read as a run row (eval::read_run_row), then the
// whole evaluation over the rows that read: the summary with its intervals, the pairs of
// policies, the Markdown and CSV, and the bench compared with itself. A bad row is refused with
// std::invalid_argument naming the key; anything else is a finding.

#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/eval/compare.hpp"
#include "overtake/eval/summary.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using nlohmann::json;
  namespace eval = overtake::eval;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  std::vector<eval::RunRow> rows;
  std::vector<std::string> policies, traffic;
  std::string line;
  while (std::getline(in, line) && rows.size() < 64) {
    const json j = json::parse(line, nullptr, false);
    if (j.is_discarded()) continue;
    try {
      rows.push_back(eval::read_run_row(j, "fuzz"));
    } catch (const std::invalid_argument&) {
      continue;
    }
    const auto add = [](std::vector<std::string>& v, const std::string& s) {
      for (const auto& x : v) {
        if (x == s) return;
      }
      v.push_back(s);
    };
    add(policies, rows.back().policy);
    add(traffic, rows.back().traffic);
  }
  if (rows.empty()) return 0;
  const json summary = eval::summarize(rows, policies, traffic);
  const json pairs = eval::pair_policies(rows, policies, traffic);
  (void)eval::summary_markdown(summary, pairs);
  (void)eval::summary_csv(summary);
  (void)eval::pairs_csv(pairs);
  eval::BenchData bench{"fuzz", json::object(), rows};
  try {
    (void)eval::compare_text(eval::compare_benches(bench, bench, {}));
  } catch (const eval::NotComparable&) {
  }
  return 0;
}
