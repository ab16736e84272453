#pragma once
// How overtake's rooms tell their caller what went wrong: a bad option (UsageError), and the
// exit codes of the command line, kept together so that every room means the same by them.

#include <stdexcept>

namespace overtake::base {

/// A bad flag value or combination; the message names the flag.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Exit codes of the command line.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;  ///< the work failed (bad file, planner failure, ...)
inline constexpr int kExitUsage = 2;    ///< bad flags or values
/// A plugin's or Python planner's plan() call would not give up (planners::PlanWatch).
inline constexpr int kExitPlannerStuck = 3;
/// Stopped by Ctrl-C (128 + SIGINT, as shells report it).
inline constexpr int kExitInterrupted = 130;

}  // namespace overtake::base
