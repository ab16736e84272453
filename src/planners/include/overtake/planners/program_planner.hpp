#pragma once
// Planner programs written for the original simulator (`--planner-cmd`), started by overtake
// for each run: in a network namespace of their own where the machine allows it (so that
// runs in parallel can all use the original's fixed port, and no other process can reach
// them), their output in a log file, driven lock-step over the protocol, stopped afterwards.

#include <filesystem>
#include <string>

#include "overtake/planners/catalog.hpp"
#include "overtake/planners/external.hpp"

namespace overtake::planners {

/// The run loop of the planner program `entry` (which has a ProgramSpec): starts the program
/// with its standard output and error going to `log` (created or truncated), waits until it
/// listens, drives the world lock-step with it, and stops it (its whole process group).
/// A program that exits, never listens, stalls or sends bad replies ends the run as
/// planner_failed with the reason; it never throws for what the program does.
[[nodiscard]] ExternalPlanner program_planner(const PlannerEntry& entry,
                                              const std::filesystem::path& log);

/// Whether runs of the planner program `entry` get networks of their own: true or false by
/// its ProgramSpec::network (automatic: where the machine allows it). UsageError when it
/// asks for isolated networks and the machine does not allow them.
[[nodiscard]] bool program_isolated(const PlannerEntry& entry);

}  // namespace overtake::planners
