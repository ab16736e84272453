// A scenarios folder as `overtake bench --scenarios DIR` reads it, without driving: the input
// is up to 8 entries separated by a line "%%", each a name line and its contents. A name that
// starts with '@' makes a link to itself (a loop), '+' a folder, '>' a link to nowhere; any
// other makes a file. The folder is listed (scenarios::list_scenario_folder), each entry is checked
// (scenarios::unreadable_scenario) and read as a scenario (run::load_scenario on the default road),
// and the verdicts are written as the suite writes them (the table, the JSON). Refusals are
// UsageError and ConfigError; anything else, a table that is not one row a verdict, or JSON that is
// not valid UTF-8, is a finding.

#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "overtake/base/errors.hpp"
#include "overtake/base/text.hpp"
#include "overtake/core/road.hpp"
#include "overtake/core/text_check.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/scenario_file.hpp"
#include "overtake/scenarios/suite.hpp"

namespace {

namespace fs = std::filesystem;
namespace base = overtake::base;
namespace run = overtake::run;
namespace scenarios = overtake::scenarios;

constexpr std::size_t kMaxEntries = 8;

// Memory-backed when the machine has it: the files are written for every input.
std::filesystem::path scratch_root() {
  std::error_code ec;
  if (std::filesystem::is_directory("/dev/shm", ec)) return "/dev/shm";
  return std::filesystem::temp_directory_path();
}

const fs::path& folder() {
  static const fs::path dir = [] {
    std::string name = (scratch_root() / "overtake-fuzz-suite.XXXXXX");
    if (::mkdtemp(name.data()) == nullptr) std::abort();
    return fs::path(name);
  }();
  return dir;
}

// A file name from the input's bytes: no '/', NUL or dot-only names; ".json" kept if given.
std::string entry_name(std::string_view raw, std::size_t index) {
  std::string name;
  for (const char c : raw.substr(0, 64)) name += (c == '/' || c == '\0') ? '_' : c;
  if (name.empty() || name == "." || name == "..") name = "entry" + std::to_string(index);
  return name;
}

void check(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(folder(), ec)) fs::remove_all(e.path(), ec);
  std::size_t from = 0;
  for (std::size_t i = 0; i < kMaxEntries && from <= text.size(); ++i) {
    std::size_t end = text.find("\n%%\n", from);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view entry = text.substr(from, end - from);
    from = end + 4;
    const std::size_t eol = entry.find('\n');
    const std::string_view head = entry.substr(0, eol);
    const std::string_view body =
        eol == std::string_view::npos ? std::string_view() : entry.substr(eol + 1);
    const char kind = head.empty() ? ' ' : head[0];
    const bool special = kind == '@' || kind == '+' || kind == '>';
    const fs::path p = folder() / entry_name(special ? head.substr(1) : head, i);
    if (kind == '@') {
      fs::create_symlink(p.filename(), p, ec);
    } else if (kind == '+') {
      fs::create_directory(p, ec);
    } else if (kind == '>') {
      fs::create_symlink("nowhere", p, ec);
    } else {
      std::ofstream out(p, std::ios::binary | std::ios::trunc);
      out.write(body.data(), static_cast<std::streamsize>(body.size()));
    }
  }
  scenarios::ScenarioFolder listed;
  try {
    listed = scenarios::list_scenario_folder(folder());
  } catch (const base::UsageError&) {
    return 0;
  }
  scenarios::SuiteOutcome outcome;
  outcome.skipped = listed.skipped;
  for (const fs::path& f : listed.files) {
    scenarios::ScenarioVerdict v;
    v.file = f.filename().string();
    v.policy = "reference";
    if (const std::string why = scenarios::unreadable_scenario(f); !why.empty()) {
      v.failures.push_back("cannot read: " + why);
    } else {
      try {
        v.name = run::load_scenario(f, overtake::core::RoadParams{}).name;
        v.pass = true;
      } catch (const run::ConfigError& e) {
        v.failures.push_back(e.what());
      }
    }
    (v.pass ? outcome.passed : outcome.failed) += 1;
    outcome.verdicts.push_back(std::move(v));
  }
  const std::string table = scenarios::suite_table(outcome);
  // The header, its rule, a row a verdict, a blank line and the count.
  check(static_cast<std::size_t>(std::count(table.begin(), table.end(), '\n')) ==
        outcome.verdicts.size() + 4);
  check(overtake::core::is_valid_utf8(base::json_text(scenarios::suite_json(outcome), 2)));
  return 0;
}
