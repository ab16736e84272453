#include "overtake/app/planners.hpp"

#include <algorithm>
#include <cctype>

#include <nlohmann/json.hpp>

#include "overtake/app/commands.hpp"
#include "overtake/plugin/plugin.hpp"
#include "overtake/python/python_policy.hpp"

namespace overtake::app {
namespace {

bool valid_name(std::string_view name) {
  if (name.empty() || name.size() > 64) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
  });
}

// The name a command gives when none is: its program's file name.
std::string name_of_command(const std::string& command) {
  std::size_t b = command.find_first_not_of(" \t");
  if (b == std::string::npos) return {};
  std::size_t e = command.find_first_of(" \t", b);
  std::string first = command.substr(b, e == std::string::npos ? std::string::npos : e - b);
  std::string stem = std::filesystem::path(first).filename().string();
  std::string out;
  for (char c : stem) out += valid_name(std::string(1, c)) ? c : '_';
  return out;
}

}  // namespace

std::string_view to_string(PlannerKind kind) {
  switch (kind) {
    case PlannerKind::builtin:
      return "builtin";
    case PlannerKind::plugin:
      return "plugin";
    case PlannerKind::python:
      return "python";
    case PlannerKind::program:
      return "program";
  }
  return "builtin";
}

std::string PlannerEntry::describe() const {
  nlohmann::json j{{"kind", to_string(kind)}};
  if (kind != PlannerKind::builtin) j["source"] = source;
  if (program) {
    j["cwd"] = program->cwd.string();
    j["port"] = program->port;
  }
  return j.dump();
}

std::string chosen_policy(const PlannerCatalog& catalog, const std::string& policy, bool given) {
  const auto added = catalog.added_names();
  if (given || added.empty()) return policy;
  if (added.size() == 1) return added.front();
  std::string names;
  for (const auto& n : added) names += (names.empty() ? "" : ", ") + n;
  throw UsageError("several planners were given (" + names + "): choose one with --policy");
}

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

void add_planner_flags(CLI::App& cmd, PlannerFlags& f, PlannerFlagSet which) {
  if (which != PlannerFlagSet::programs) {
    cmd.add_option("--policy-lib", f.libs,
                   "[NAME=]PATH: a C++ planner plugin (a shared library built against\n"
                   "overtake/planner_plugin.h), run in-process; named by the plugin unless NAME=")
        ->allow_extra_args(false)
        ->take_all();
    cmd.add_option("--policy-py", f.python,
                   "[NAME=]MODULE:FUNCTION or [NAME=]FILE.py:FUNCTION: a Python planner (a\n"
                   "callable taking the telemetry dict as the original sends it and returning\n"
                   "(path_x, path_y); a class: one instance per run), run in-process; MODULE is\n"
                   "imported from the current directory or PYTHONPATH, FILE.py from its folder;\n"
                   "named after the module unless NAME=")
        ->allow_extra_args(false)
        ->take_all();
  }
  if (which == PlannerFlagSet::in_process) return;
  cmd.add_option("--planner-cmd", f.commands,
                 "[NAME=]CMD: a planner program written for the original simulator; overtake\n"
                 "starts it for each run (sh -c CMD) in a network namespace of its own, drives it\n"
                 "over the protocol on --planner-port, and stops it afterwards")
      ->allow_extra_args(false)
      ->take_all();
  cmd.add_option("--planner-cwd", f.cwd, "Working directory of --planner-cmd programs")
      ->check(CLI::ExistingDirectory);
  cmd.add_option("--planner-port", f.port, "Port the --planner-cmd programs listen on")
      ->check(CLI::Range(1, 65535))
      ->capture_default_str();
  cmd.add_option("--planner-network", f.network,
                 "auto: each --planner-cmd run in a network of its own where the machine allows\n"
                 "it (runs in parallel, nothing else can reach the planner), else the host's\n"
                 "(one run at a time); isolated: always its own (fail when impossible); host")
      ->check(CLI::IsMember({"auto", "isolated", "host"}))
      ->capture_default_str();
  cmd.add_option("--planner-log-max-mb", f.log_max_mb,
                 "Each run's log of a --planner-cmd program is cut at this size (MB); the rest\n"
                 "of its output is dropped")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  if (which == PlannerFlagSet::programs) return;  // sim: --connect-timeout, --reply-timeout
  cmd.add_option("--planner-start-timeout", f.start_timeout_s,
                 "Seconds a --planner-cmd program has to start listening")
      ->check(CLI::Range(0.1, 3600.0))
      ->capture_default_str();
  cmd.add_option("--planner-reply-timeout", f.reply_timeout_s,
                 "Seconds a --planner-cmd program has for each reply")
      ->check(CLI::Range(0.01, 3600.0))
      ->capture_default_str();
}

std::shared_ptr<const PlannerCatalog> catalog_from_flags(const PlannerFlags& f) {
  auto catalog = std::make_shared<PlannerCatalog>();
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
    e.make = std::move(loaded.make);
    catalog->add(std::move(e), "--policy-lib");
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
    e.make = std::move(loaded.make);
    catalog->add(std::move(e), "--policy-py");
  }
  for (const auto& text : f.commands) {
    auto [name, command] = split_named(text);
    if (command.find_first_not_of(" \t") == std::string::npos) {
      throw UsageError("--planner-cmd: no command in '" + text + "'");
    }
    PlannerEntry e;
    e.name = name.empty() ? name_of_command(command) : name;
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
    catalog->add(std::move(e), "--planner-cmd");
  }
  return catalog;
}

}  // namespace overtake::app
