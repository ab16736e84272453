#include <CLI/CLI.hpp>

#include "overtake/app/cli.hpp"
#include "overtake/planners/catalog.hpp"

namespace overtake::app {

using planners::PlannerFlags;
using planners::PlannerFlagSet;

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
    cmd.add_option("--planner-params", f.params,
                   "NAME=JSON: parameters of a --policy-py or --policy-lib planner, a JSON object\n"
                   "of numbers by name ('mine={\"speed_mps\":20.5}'): a Python planner's keyword\n"
                   "arguments, a plugin's setup config_json")
        ->allow_extra_args(false)
        ->take_all();
  }
  const auto reply_timeout = [&] {
    cmd.add_option("--planner-reply-timeout", f.reply_timeout_s,
                   "Seconds a planner has for each reply: a --planner-cmd program's, or one\n"
                   "plan() call of a --policy-py planner (then interrupted: its run fails) or\n"
                   "a --policy-lib plugin (which cannot be stopped in-process: overtake ends,\n"
                   "keeping every finished run); Ctrl-C stops either within a second")
        ->check(CLI::Range(0.01, 3600.0))
        ->capture_default_str();
  };
  if (which == PlannerFlagSet::in_process) {
    reply_timeout();
    return;
  }
  cmd.add_option("--planner-cmd", f.commands,
                 "CMD: a planner program written for the original simulator; overtake starts it\n"
                 "for each run (sh -c CMD, so 'OMP_NUM_THREADS=1 ./planner' sets a variable)\n"
                 "in namespaces of its own, drives it over the protocol on --planner-port, and\n"
                 "stops it and everything it started afterwards; named after its program\n"
                 "unless --planner-name")
      ->allow_extra_args(false)
      ->take_all();
  cmd.add_option("--planner-name", f.names,
                 "NAME: the name of a --planner-cmd program in reports and tables; give one\n"
                 "per --planner-cmd, in the same order")
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
  reply_timeout();
}

}  // namespace overtake::app
