#pragma once
// Python planners in-process (`--policy-py MODULE:FUNCTION`): the interpreter embedded, the
// callable given the telemetry as the original sends it, its path taken back as a policy's.

#include <functional>
#include <map>
#include <stdexcept>
#include <string>

#include "overtake/planner/policy.hpp"

namespace overtake::python {

/// A Python planner that cannot be loaded or used; the message says what is wrong.
class PythonError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A Python planner: its name and a factory of policy instances.
struct LoadedPython {
  std::string name;
  planner::PolicyFactory make;
  /// The factory of the same planner given keyword arguments (`plan(telemetry, **kw)`, or
  /// `Planner(**kw)` for a class); throws PythonError when the callable cannot take them.
  std::function<planner::PolicyFactory(const std::map<std::string, double>&)> with_keywords;
};

/// Imports MODULE and finds FUNCTION (`spec` is MODULE:FUNCTION). Throws PythonError.
[[nodiscard]] LoadedPython load_python_policy(const std::string& spec);

}  // namespace overtake::python
