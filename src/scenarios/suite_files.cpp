// The files of a scenario suite, without driving anything: the folder listed, what cannot be
// read, the table and the verdicts written (the fuzz harness `scenario_folder` links it alone).

#include <algorithm>
#include <sstream>
#include <string_view>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "overtake/scenarios/suite.hpp"

namespace overtake::scenarios {

using base::fixed_text;
using base::read_file;
using base::UsageError;
using run::parse_json_text;
namespace {

using nlohmann::json;

/// A markdown table cell: a line break or a '|' in the text would end the row or the cell.
std::string table_cell(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '|') {
      out += "\\|";
    } else if (c == '\r' || c == '\n') {
      if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      out += "<br>";
    } else {
      out += c;
    }
  }
  return out;
}

}  // namespace

// True when `file` is a suite's verdicts (suite.json as run_suite writes it).
bool is_suite_verdicts(const std::filesystem::path& file) {
  try {
    const json j = parse_json_text(read_file(file), file.string());
    return j.is_object() && j.contains("verdicts") && j["verdicts"].is_array() &&
           j.contains("passed") && j.contains("failed") && j.contains("interrupted");
  } catch (const std::exception&) {
    return false;
  }
}

// True when `file` is a suite's table (suite.md as run_suite writes it).
bool is_suite_table(const std::filesystem::path& file) {
  try {
    const std::string text = read_file(file);
    return text.compare(0, kSuiteTableHeader.size(), kSuiteTableHeader) == 0 &&
           text.size() > kSuiteTableHeader.size() && text[kSuiteTableHeader.size()] == '\n';
  } catch (const std::exception&) {
    return false;
  }
}

// Why `file` cannot be read as a scenario (it is not a regular file, or its status cannot be
// read: a dangling link, a loop of links); empty when it can be tried.
std::string unreadable_scenario(const std::filesystem::path& file) {
  std::error_code ec;
  const auto st = std::filesystem::status(file, ec);
  if (ec) return ec.message();
  if (std::filesystem::is_directory(st)) return "a folder, not a file";
  if (!std::filesystem::is_regular_file(st)) return "not a regular file";
  return {};
}

ScenarioFolder list_scenario_folder(const std::filesystem::path& dir) {
  // Every *.json entry is a scenario, whatever it is: one that cannot be read (a folder, a
  // loop of links) fails its rows. A suite's own verdicts (suite.json) are not a scenario.
  ScenarioFolder out;
  std::error_code ec;
  std::filesystem::directory_iterator it(dir, ec), end;
  for (; !ec && it != end; it.increment(ec)) {
    const std::filesystem::path& p = it->path();
    if (p.extension() != ".json") continue;
    if (p.filename() == kSuiteVerdictsFile && is_suite_verdicts(p)) {
      out.skipped.push_back(p.filename().string());
      continue;
    }
    out.files.push_back(p);
  }
  if (ec) throw UsageError("--scenarios: " + dir.string() + ": " + ec.message());
  if (out.files.empty()) {
    throw UsageError("--scenarios: " + dir.string() + " holds no scenario files (*.json)");
  }
  std::sort(out.files.begin(), out.files.end());
  return out;
}

std::string suite_table(const SuiteOutcome& o) {
  std::ostringstream os;
  os << kSuiteTableHeader << "\n"
     << "|---|---|---|---:|---:|---:|---|\n";
  for (const ScenarioVerdict& v : o.verdicts) {
    std::string why;
    for (const std::string& f : v.failures) why += (why.empty() ? "" : "; ") + f;
    if (!v.replay.empty()) why += " (replay: " + v.replay + ")";
    if (!v.warm_up.empty() && !(v.pass && v.warm_up.find("NOT IN STEP") == std::string::npos)) {
      why += (why.empty() ? "warm-up: " : "; warm-up: ") + v.warm_up;
    }
    os << "| " << table_cell(v.file) << " | " << table_cell(v.policy) << " | "
       << (v.pass ? "pass" : "**FAIL**") << " | " << v.incidents << " | " << v.collisions << " ("
       << v.at_fault_collisions << ") | " << fixed_text(v.distance_m, 1) << " | " << table_cell(why)
       << " |\n";
  }
  os << "\n"
     << o.passed << " passed, " << o.failed << " failed"
     << (o.interrupted ? " (interrupted: not every scenario ran)" : "") << "\n";
  return os.str();
}

nlohmann::json suite_json(const SuiteOutcome& o) {
  json rows = json::array();
  for (const ScenarioVerdict& v : o.verdicts) {
    rows.push_back({{"file", v.file},
                    {"name", v.name},
                    {"policy", v.policy},
                    {"pass", v.pass},
                    {"failures", v.failures},
                    {"incidents", v.incidents},
                    {"collisions", v.collisions},
                    {"at_fault_collisions", v.at_fault_collisions},
                    {"distance_m", v.distance_m},
                    {"duration_s", v.duration_s},
                    {"replay", v.replay},
                    {"warm_up", v.warm_up.empty() ? json(nullptr) : json(v.warm_up)}});
  }
  return {{"passed", o.passed},
          {"failed", o.failed},
          {"interrupted", o.interrupted},
          {"verdicts", rows}};
}

}  // namespace overtake::scenarios
