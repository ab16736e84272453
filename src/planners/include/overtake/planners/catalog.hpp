#pragma once
// Where the planners of a run come from: the built-in policies, C++ plugins (`--policy-lib`),
// Python planners (`--policy-py`) and planner programs written for the original simulator
// (`--planner-cmd`). Each has a name, as it appears in reports and bench tables; `drive`,
// `bench`, `serve` and `sim` resolve a name through one catalog.

#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/planner/policy.hpp"
#include "overtake/sandbox/planner_process.hpp"

namespace overtake::planners {

/// How a planner is reached.
enum class PlannerKind {
  builtin,  ///< a policy of this build
  plugin,   ///< a C++ plugin (overtake/planner_plugin.h), in-process
  python,   ///< a Python callable, in-process
  program,  ///< a planner program over the original protocol, started by overtake per run
};

[[nodiscard]] std::string_view to_string(PlannerKind kind);
/// The flag that brings a planner of this kind: --policy-lib, --policy-py or --planner-cmd
/// (empty for a built-in policy).
[[nodiscard]] std::string_view flag_of(PlannerKind kind);

/// A planner program started for each run (`--planner-cmd`).
struct ProgramSpec {
  std::string command;            ///< run by /bin/sh -c
  std::filesystem::path cwd;      ///< empty: the current directory
  int port = 4567;                ///< where the program listens (the original's fixed port)
  double start_timeout_s = 20.0;  ///< to start listening
  double reply_timeout_s = 5.0;   ///< for each reply
  sandbox::PlannerNetwork network = sandbox::PlannerNetwork::automatic;
  double log_max_mb = 64.0;  ///< each run's log is cut at this size
  bool realtime = false;     ///< drive it at real time (sim --realtime) instead of lock-step
};

/// One planner a run can be given.
struct PlannerEntry {
  std::string name;
  PlannerKind kind = PlannerKind::builtin;
  std::string source;           ///< the plugin's path, module:function, or the command
  planner::PolicyFactory make;  ///< builtin, plugin and python
  /// The factory given parameters by name (`overtake tune`): a Python planner's keyword
  /// arguments (throws when the callable cannot take them), a plugin's setup config_json.
  /// Empty for the others.
  std::function<planner::PolicyFactory(const std::map<std::string, double>&)> with_keywords;
  /// The parameters `make` was given (`--planner-params`, a tune's trial); empty: none.
  std::map<std::string, double> params;
  std::optional<ProgramSpec> program;
  /// A plugin's or Python planner's longest plan() call: past it the call is interrupted (a
  /// Python planner) or overtake ends (a plugin: code in this process cannot be stopped).
  double reply_timeout_s = 5.0;
  /// What the run's provenance records of it (kind, source, ...): a JSON object's text.
  [[nodiscard]] std::string describe() const;
  /// How messages name it: "the plugin NAME (SOURCE)", "the Python planner NAME (SOURCE)".
  [[nodiscard]] std::string label() const;
  /// This planner with `values` added to its parameters (replacing those of the same name):
  /// `make` from with_keywords. Throws what with_keywords throws (a keyword a Python callable
  /// cannot take); std::logic_error for a planner without with_keywords.
  [[nodiscard]] PlannerEntry with_params(const std::map<std::string, double>& values) const;
  /// Whether its plan() calls are watched (a planner from outside in this process).
  [[nodiscard]] bool watched() const {
    return kind == PlannerKind::plugin || kind == PlannerKind::python;
  }
};

/// The planners a command knows: the built-in policies and those its flags brought.
class PlannerCatalog {
 public:
  PlannerCatalog();
  /// Adds an entry; UsageError (naming `flag`) when its name is taken or not a valid name
  /// (letters, digits, `_`, `-`, `.`).
  void add(PlannerEntry entry, std::string_view flag);
  /// The entry of that name (built-in policies included), or null.
  [[nodiscard]] const PlannerEntry* find(std::string_view name) const;
  /// The entry of that name; UsageError "--policy: unknown policy 'NAME' (available: ...)"
  /// when there is none (every command checks a policy name this way).
  [[nodiscard]] const PlannerEntry& require(std::string_view name) const;
  /// The names the flags brought, in the order given.
  [[nodiscard]] std::vector<std::string> added_names() const;
  /// Every name: built-in, then added.
  [[nodiscard]] std::vector<std::string> all_names() const;
  /// all_names() joined with ", " (for messages).
  [[nodiscard]] std::string names_text() const;
  [[nodiscard]] bool has_programs() const;

 private:
  std::deque<PlannerEntry> builtin_;
  std::deque<PlannerEntry> added_;  ///< a deque: entries found stay where they are
};

/// The flags that bring planners: --policy-lib and --policy-py (each `NAME=VALUE` or
/// `VALUE`, the name then coming from the value), and (`programs`) --planner-cmd with
/// --planner-name, --planner-cwd and --planner-port. A command is never split at `=`: a
/// shell command may start with a variable (`OMP_NUM_THREADS=1 ./planner`).
struct PlannerFlags {
  std::vector<std::string> libs;
  std::vector<std::string> python;
  /// --planner-params: `NAME=JSON`, the parameters of a --policy-py or --policy-lib planner (a
  /// JSON object of numbers by name: its keyword arguments, its setup config_json).
  std::vector<std::string> params;
  std::vector<std::string> commands;
  std::vector<std::string> names;  ///< --planner-name: none, or one per command
  std::string cwd;
  int port = 4567;
  double start_timeout_s = 20.0;
  double reply_timeout_s = 5.0;
  std::string network = "auto";
  double log_max_mb = 64.0;
  bool realtime = false;  ///< not a flag of its own: `sim --realtime`
};

/// Which planner flags a command takes.
enum class PlannerFlagSet {
  in_process,  ///< --policy-lib, --policy-py (drive, serve)
  programs,    ///< --planner-cmd and its options (sim)
  all,         ///< both (bench)
};

/// The catalog the flags give (plugins loaded, Python modules imported: a bad one is refused
/// here with its reason, before any run).
[[nodiscard]] std::shared_ptr<const PlannerCatalog> catalog_from_flags(const PlannerFlags& flags);

/// The policy a single-planner command (`drive`, `serve`, `sim`) runs: `policy` when it was
/// given (`given`), else the one planner the flags brought, else `policy` (the default).
/// UsageError when the flags brought several and --policy names none of them.
[[nodiscard]] std::string chosen_policy(const PlannerCatalog& catalog, const std::string& policy,
                                        bool given);

/// How a command line brings a planner: its kind, name and source (as the run's provenance
/// records them: `config.planner`).
struct PlannerCall {
  PlannerKind kind = PlannerKind::builtin;
  std::string name;
  std::string source;            ///< a plugin's path, module:function, or a program's command
  std::string cwd;               ///< a program's working directory ("" or "." : the current one)
  int port = 4567;               ///< where a program listens
  double reply_timeout_s = 5.0;  ///< a program's longest wait for one reply (`sim`'s is 2 s)
};
/// The call of an entry.
[[nodiscard]] PlannerCall call_of(const PlannerEntry& entry);
/// The call of a planner named `name` that PlannerEntry::describe described (a JSON object:
/// kind, source, cwd, port); a built-in policy when `described` is not such an object.
[[nodiscard]] PlannerCall call_from_description(const std::string& name,
                                                const nlohmann::json& described);
/// The start of the command that drives with the planner, flags quoted for sh:
/// `overtake drive --policy NAME` (built-in), `overtake drive --policy-lib NAME=LIB`,
/// `overtake drive --policy-py NAME=MODULE:FN`, `overtake sim --planner-cmd CMD --planner-name
/// NAME --reply-timeout S` (the program's, as bench and hunt gave it; with --planner-cwd and
/// --planner-port when they are not the defaults).
[[nodiscard]] std::string planner_command_line(const PlannerCall& call);

/// Splits `NAME=VALUE` (NAME: letters, digits, `_`, `-`, `.`; no space before the `=`) into
/// its parts; without such a prefix the name is empty.
[[nodiscard]] std::pair<std::string, std::string> split_named(const std::string& text);

}  // namespace overtake::planners
