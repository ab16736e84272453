#pragma once
// What two bench folders must agree on when they ran the same sweep: their runs and their
// summary, with what measures time (and the host and revision that made each row) left out.

#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "overtake/base/io.hpp"

namespace overtake::test {

/// runs.jsonl, one line per run, without each row's timing and provenance.
inline std::string stable_runs(const std::filesystem::path& dir) {
  std::ifstream in(dir / "runs.jsonl");
  std::string line, text;
  while (std::getline(in, line)) {
    nlohmann::json j = nlohmann::json::parse(line);
    j.erase("timing");
    j.erase("provenance");
    text += j.dump() + "\n";
  }
  return text;
}

/// summary.json without the planners' timing.
inline std::string untimed_summary(const std::filesystem::path& dir) {
  nlohmann::json s = nlohmann::json::parse(base::read_file(dir / "summary.json"));
  for (auto& r : s["rows"]) r.erase("timing");
  return s.dump();
}

}  // namespace overtake::test
