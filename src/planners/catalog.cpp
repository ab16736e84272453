#include "overtake/planners/catalog.hpp"

#include "overtake/base/io.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "overtake/base/errors.hpp"
#include "overtake/base/text.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/planners/program_planner.hpp"
#include "overtake/plugin/plugin.hpp"
#include "overtake/python/python_policy.hpp"
#include "overtake/sandbox/planner_process.hpp"

namespace overtake::planners {

using base::fixed_text;
using base::json_text;
using base::shell_quote;
using base::UsageError;
using sandbox::parse_planner_network;
using sandbox::PlannerNetwork;
namespace {

bool valid_name(std::string_view name) {
  if (name.empty() || name.size() > 64) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
  });
}

// The words of a shell command, split where sh would split them (quotes and backslashes
// kept out of the split, not interpreted further): enough to find the program it runs.
std::vector<std::string> shell_words(const std::string& command) {
  std::vector<std::string> words;
  std::string word;
  bool in_word = false;
  char quote = 0;
  for (std::size_t i = 0; i < command.size(); ++i) {
    const char c = command[i];
    if (quote != 0) {
      if (c == quote)
        quote = 0;
      else
        word += c;
      continue;
    }
    if (c == '\'' || c == '"') {
      quote = c;
      in_word = true;
    } else if (c == '\\' && i + 1 < command.size()) {
      word += command[++i];
      in_word = true;
    } else if (c == ' ' || c == '\t' || c == '\n') {
      if (in_word) words.push_back(word);
      word.clear();
      in_word = false;
    } else {
      word += c;
      in_word = true;
    }
  }
  if (in_word) words.push_back(word);
  return words;
}

// `NAME=value` as sh reads a word before the command: a variable for the command.
bool is_assignment(const std::string& word) {
  const std::size_t eq = word.find('=');
  if (eq == std::string::npos || eq == 0) return false;
  if (std::isdigit(static_cast<unsigned char>(word[0]))) return false;
  return std::all_of(word.begin(), word.begin() + static_cast<std::ptrdiff_t>(eq), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

// The program a command runs: its first word after variable assignments and `exec`/`env`.
std::string program_of_command(const std::string& command) {
  for (const std::string& w : shell_words(command)) {
    if (is_assignment(w) || w == "exec" || w == "env") continue;
    return w;
  }
  return {};
}

// The name a command gives when none is: its program's file name.
std::string name_of_command(const std::string& command) {
  const std::string stem = std::filesystem::path(program_of_command(command)).filename().string();
  std::string out;
  for (char c : stem) out += valid_name(std::string(1, c)) ? c : '_';
  return out;
}

/// Each kind of planner: its name in records and the flag that brings it.
struct KindText {
  PlannerKind kind;
  std::string_view name;
  std::string_view flag;
};
constexpr std::array<KindText, 4> kKindTexts{{{PlannerKind::builtin, "builtin", ""},
                                              {PlannerKind::plugin, "plugin", "--policy-lib"},
                                              {PlannerKind::python, "python", "--policy-py"},
                                              {PlannerKind::program, "program", "--planner-cmd"}}};

const KindText& text_of(PlannerKind kind) {
  for (const KindText& t : kKindTexts)
    if (t.kind == kind) return t;
  return kKindTexts.front();
}

}  // namespace

std::string_view to_string(PlannerKind kind) {
  return text_of(kind).name;
}

std::string_view flag_of(PlannerKind kind) {
  return text_of(kind).flag;
}

PlannerCall call_of(const PlannerEntry& entry) {
  PlannerCall c;
  c.kind = entry.kind;
  c.name = entry.name;
  c.source = entry.source;
  if (entry.program) {
    c.cwd = entry.program->cwd.string();
    c.port = entry.program->port;
    c.reply_timeout_s = entry.program->reply_timeout_s;
  }
  return c;
}

PlannerCall call_from_description(const std::string& name, const nlohmann::json& described) {
  PlannerCall call{PlannerKind::builtin,         name, {}, {}, ProgramSpec{}.port,
                   ProgramSpec{}.reply_timeout_s};
  if (!described.is_object()) return call;
  const auto text = [&](const char* key) {
    const auto it = described.find(key);
    return it != described.end() && it->is_string() ? it->get<std::string>() : std::string();
  };
  const std::string kind = text("kind");
  call.kind = kind == "plugin"    ? PlannerKind::plugin
              : kind == "python"  ? PlannerKind::python
              : kind == "program" ? PlannerKind::program
                                  : PlannerKind::builtin;
  call.source = text("source");
  call.cwd = text("cwd");
  const auto port = described.find("port");
  if (port != described.end() && port->is_number_integer()) call.port = port->get<int>();
  return call;
}

std::string planner_command_line(const PlannerCall& c) {
  const std::string named = shell_quote(c.name + "=" + c.source);
  switch (c.kind) {
    case PlannerKind::plugin:
      return "overtake drive --policy-lib " + named;
    case PlannerKind::python:
      return "overtake drive --policy-py " + named;
    case PlannerKind::program: {
      std::string cmd = "overtake sim --planner-cmd " + shell_quote(c.source) + " --planner-name " +
                        shell_quote(c.name) + " --reply-timeout " +
                        fixed_text(c.reply_timeout_s, 1);
      if (!c.cwd.empty() && c.cwd != ".") cmd += " --planner-cwd " + shell_quote(c.cwd);
      if (c.port != ProgramSpec{}.port) cmd += " --planner-port " + std::to_string(c.port);
      return cmd;
    }
    case PlannerKind::builtin:
      break;
  }
  return "overtake drive --policy " + shell_quote(c.name);
}

std::string PlannerEntry::describe() const {
  nlohmann::json j{{"kind", to_string(kind)}};
  if (kind != PlannerKind::builtin) j["source"] = source;
  if (!params.empty()) j["params"] = params;
  if (program) {
    j["cwd"] = program->cwd.string();
    j["port"] = program->port;
    // Where it ran: on the host's network, whatever listened on the port was taken for it.
    j["network"] = program_isolated(*this) ? "isolated" : "host";
  }
  return json_text(j);
}

PlannerEntry PlannerEntry::with_params(const std::map<std::string, double>& values) const {
  if (!with_keywords) throw std::logic_error(label() + " takes no parameters");
  PlannerEntry e = *this;
  for (const auto& [key, value] : values) e.params[key] = value;
  e.make = with_keywords(e.params);
  return e;
}

std::string PlannerEntry::label() const {
  switch (kind) {
    case PlannerKind::plugin:
      return "the plugin " + name + " (" + source + ")";
    case PlannerKind::python:
      return "the Python planner " + name + " (" + source + ")";
    case PlannerKind::program:
      return "the planner program " + name + " (" + source + ")";
    case PlannerKind::builtin:
      break;
  }
  return "the policy " + name;
}

std::string chosen_policy(const PlannerCatalog& catalog, const std::string& policy, bool given) {
  const auto added = catalog.added_names();
  if (given || added.empty()) return policy;
  if (added.size() == 1) return added.front();
  std::string names;
  for (const auto& n : added) names += (names.empty() ? "" : ", ") + n;
  throw UsageError("several planners were given (" + names + "): choose one with --policy");
}

namespace {

// --planner-params: each NAME=JSON as numbers by name, by planner name.
std::map<std::string, std::map<std::string, double>> parse_planner_params(
    const std::vector<std::string>& texts) {
  std::map<std::string, std::map<std::string, double>> out;
  for (const std::string& text : texts) {
    const auto bad = [&](const std::string& why) {
      return UsageError("--planner-params: '" + text + "': " + why +
                        R"( (expected NAME={"key":number,...}))");
    };
    const std::size_t eq = text.find('=');
    if (eq == std::string::npos) throw bad("no '=' after the planner's name");
    const std::string name = text.substr(0, eq);
    if (!valid_name(name)) throw bad("'" + name + "' is not a planner name");
    if (out.count(name) != 0) throw bad("the planner " + name + " was given parameters before");
    const nlohmann::json j = nlohmann::json::parse(text.substr(eq + 1), nullptr, false);
    if (j.is_discarded() || !j.is_object()) throw bad("not a JSON object of numbers");
    std::map<std::string, double>& values = out[name];
    for (const auto& [key, value] : j.items()) {
      if (!value.is_number() || !std::isfinite(value.get<double>())) {
        throw bad("the value of '" + key + "' is not a finite number");
      }
      values[key] = value.get<double>();
    }
  }
  return out;
}

// `e` with the parameters --planner-params gave it, if any (taken out of `params`).
PlannerEntry with_given_params(PlannerEntry e,
                               std::map<std::string, std::map<std::string, double>>& params) {
  const auto it = params.find(e.name);
  if (it == params.end()) return e;
  try {
    e = e.with_params(it->second);
  } catch (const std::exception& error) {
    throw UsageError("--planner-params: " + e.label() + ": " + error.what());
  }
  params.erase(it);
  return e;
}

}  // namespace

std::pair<std::string, std::string> split_named(const std::string& text) {
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0) return {"", text};
  const std::string name = text.substr(0, eq);
  if (!valid_name(name)) return {"", text};
  return {name, text.substr(eq + 1)};
}

void PlannerCatalog::add(PlannerEntry entry, std::string_view flag) {
  if (!valid_name(entry.name)) {
    throw UsageError(std::string(flag) + ": '" + entry.name +
                     "' is not a usable planner name (letters, digits, _, - and ., at most 64; "
                     "give one as NAME=...)");
  }
  if (find(entry.name)) {
    throw UsageError(std::string(flag) + ": the name '" + entry.name +
                     "' is already taken by another planner (give another as NAME=...)");
  }
  added_.push_back(std::move(entry));
}

PlannerCatalog::PlannerCatalog() {
  for (const auto& p : planner::list_policies()) {
    PlannerEntry e;
    e.name = p.name;
    e.kind = PlannerKind::builtin;
    e.source = p.name;
    e.make = planner::builtin_policy_factory(p.name);
    builtin_.push_back(std::move(e));
  }
}

const PlannerEntry* PlannerCatalog::find(std::string_view name) const {
  for (const auto* list : {&builtin_, &added_}) {
    for (const auto& e : *list) {
      if (e.name == name) return &e;
    }
  }
  return nullptr;
}

const PlannerEntry& PlannerCatalog::require(std::string_view name) const {
  const PlannerEntry* entry = find(name);
  if (!entry) {
    throw UsageError("--policy: " + planner::unknown_policy_text(name, names_text()));
  }
  return *entry;
}

std::vector<std::string> PlannerCatalog::added_names() const {
  std::vector<std::string> out;
  for (const auto& e : added_) out.push_back(e.name);
  return out;
}

std::vector<std::string> PlannerCatalog::all_names() const {
  std::vector<std::string> out;
  for (const auto* list : {&builtin_, &added_}) {
    for (const auto& e : *list) out.push_back(e.name);
  }
  return out;
}

std::string PlannerCatalog::names_text() const {
  std::string out;
  for (const auto& n : all_names()) out += (out.empty() ? "" : ", ") + n;
  return out;
}

bool PlannerCatalog::has_programs() const {
  return std::any_of(added_.begin(), added_.end(),
                     [](const PlannerEntry& e) { return e.kind == PlannerKind::program; });
}

std::shared_ptr<const PlannerCatalog> catalog_from_flags(const PlannerFlags& f) {
  auto catalog = std::make_shared<PlannerCatalog>();
  auto params = parse_planner_params(f.params);
  for (const auto& text : f.libs) {
    auto [name, path] = split_named(text);
    if (path.empty()) throw UsageError("--policy-lib: no library path in '" + text + "'");
    plugin::LoadedPlugin loaded;
    try {
      loaded = plugin::load_plugin(path);
    } catch (const plugin::PluginError& e) {
      throw UsageError(std::string("--policy-lib: ") + e.what());
    }
    PlannerEntry e;
    e.name = name.empty() ? loaded.name : name;
    e.kind = PlannerKind::plugin;
    e.source = path;
    e.reply_timeout_s = f.reply_timeout_s;
    e.make = std::move(loaded.make);
    e.with_keywords =
        [with_config = std::move(loaded.with_config)](const std::map<std::string, double>& values) {
          nlohmann::json j = nlohmann::json::object();
          for (const auto& [key, value] : values) j[key] = value;
          return with_config(j.dump());
        };
    catalog->add(with_given_params(std::move(e), params), flag_of(PlannerKind::plugin));
  }
  for (const auto& text : f.python) {
    auto [name, spec] = split_named(text);
    if (spec.empty()) throw UsageError("--policy-py: no MODULE:FUNCTION in '" + text + "'");
    python::LoadedPython loaded;
    try {
      loaded = python::load_python_policy(spec);
    } catch (const python::PythonError& e) {
      throw UsageError(std::string("--policy-py: ") + e.what());
    }
    PlannerEntry e;
    e.name = name.empty() ? loaded.name : name;
    e.kind = PlannerKind::python;
    e.source = spec;
    e.reply_timeout_s = f.reply_timeout_s;
    e.make = std::move(loaded.make);
    e.with_keywords = std::move(loaded.with_keywords);
    catalog->add(with_given_params(std::move(e), params), flag_of(PlannerKind::python));
  }
  if (!params.empty()) {
    throw UsageError("--planner-params: '" + params.begin()->first +
                     "' names no --policy-py or --policy-lib planner (a planner program takes its "
                     "parameters in its command, a built-in policy by --config)");
  }
  if (!f.names.empty() && f.names.size() != f.commands.size()) {
    throw UsageError("--planner-name: " + std::to_string(f.names.size()) + " names for " +
                     std::to_string(f.commands.size()) +
                     " --planner-cmd programs: give one per program, in the same order");
  }
  for (std::size_t i = 0; i < f.commands.size(); ++i) {
    const std::string& command = f.commands[i];
    const std::string name = f.names.empty() ? std::string() : f.names[i];
    if (command.find_first_not_of(" \t") == std::string::npos) {
      throw UsageError("--planner-cmd: no command in '" + command + "'");
    }
    if (program_of_command(command).empty()) {
      throw UsageError("--planner-cmd: '" + command +
                       "' only sets shell variables and runs no program (name a planner with "
                       "--planner-name NAME; --planner-cmd takes the command alone)");
    }
    PlannerEntry e;
    e.name = name.empty() ? name_of_command(command) : name;
    e.reply_timeout_s = f.reply_timeout_s;
    e.kind = PlannerKind::program;
    e.source = command;
    ProgramSpec p;
    p.command = command;
    if (!f.cwd.empty()) p.cwd = std::filesystem::absolute(f.cwd);
    p.port = f.port;
    p.start_timeout_s = f.start_timeout_s;
    p.reply_timeout_s = f.reply_timeout_s;
    p.realtime = f.realtime;
    p.log_max_mb = f.log_max_mb;
    p.network = parse_planner_network(f.network).value_or(PlannerNetwork::automatic);
    e.program = p;
    catalog->add(std::move(e), flag_of(PlannerKind::program));
  }
  return catalog;
}

}  // namespace overtake::planners
