#pragma once
// Between the planners' structs and Python: the telemetry as the dict the original's JSON
// would give (the same keys, units and rounding, plus numpy arrays), a planner's answer read
// back as a path, and a Python callable as a planner::Policy. Shared by `--policy-py` (the
// embedded interpreter) and the Python module. Every function here needs the GIL unless it
// says otherwise.

#include <pybind11/pybind11.h>

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/telemetry.hpp"
#include "overtake/planner/policy.hpp"

namespace overtake::python {

/// The most path points a planner may answer (the protocol's limit too).
inline constexpr std::size_t kMaxPathPoints = 10'000;

/// The telemetry as the original sends it: x, y (m), yaw (degrees), speed (mph), s, d (m),
/// previous_path_x/_y (lists, m), end_path_s/_d, sensor_fusion (rows [id, x, y, vx, vy, s,
/// d], m and m/s), in the original's key order; then, when numpy can be imported,
/// "previous_path_array" ((N, 2) float64) and "sensor_fusion_array" ((N, 7) float64).
[[nodiscard]] pybind11::dict telemetry_to_dict(const core::Telemetry& telemetry);

/// The telemetry read back from such a dict (the arrays are not read), converted as the
/// protocol's codec converts the original's JSON. Throws PythonError naming a missing or
/// wrong key.
[[nodiscard]] core::Telemetry telemetry_from_dict(pybind11::handle dict);

/// A planner's answer as a path: a pair (path_x, path_y) of equally long sequences (lists,
/// tuples or numpy arrays) of finite numbers, at most kMaxPathPoints. Throws PythonError
/// saying what is wrong.
[[nodiscard]] std::vector<core::Vec2> path_from_python(pybind11::handle answer);

/// The Python exception being handled, as "Type: message (file, line N, in function)".
[[nodiscard]] std::string describe(const pybind11::error_already_set& e);

/// A Python object kept alive from C++, released under the GIL from any thread (also without
/// the GIL held).
using SharedObject = std::shared_ptr<pybind11::object>;
[[nodiscard]] SharedObject share(pybind11::object object);

/// A KeyboardInterrupt or SystemExit met in Python during a drive that Python started
/// (raised by the planner, or by Python's own Ctrl-C handler): it means "stop", not "the
/// planner failed", so it sets the run's stop flag and is kept, to be raised again to the
/// drive's caller once the run has stopped. Thread-safe.
class DriveInterruption {
 public:
  /// Whether `e` is such an exception (KeyboardInterrupt, SystemExit). Needs the GIL.
  [[nodiscard]] static bool stops_the_drive(const pybind11::error_already_set& e);
  /// Keeps `e` (the first one kept wins) and sets the stop flag. Needs the GIL.
  void keep(const pybind11::error_already_set& e);
  /// The flag to give the run as its stop flag; set by keep().
  [[nodiscard]] const std::atomic<bool>* stop_flag() const { return &stop_; }
  /// Throws the kept exception (the same Python object) when there is one. Needs the GIL.
  void raise_if_kept();

 private:
  std::mutex mutex_;
  std::optional<pybind11::error_already_set> kept_;
  std::atomic<bool> stop_{false};
};

/// A factory of policies that call `callable` with the telemetry dict each cycle, under the
/// GIL (taken for the call, released otherwise; any thread). A Python exception, a wrong
/// answer or a NaN ends the run as planner_failed with the Python error's text. When
/// `callable` is a class, each policy calls a new instance of it (state per run). With
/// `stops` (may be null), a KeyboardInterrupt or SystemExit goes there instead of being a
/// failure. The policies can be interrupted (planner::Policy::interrupt): the running call
/// then raises TimeoutError or KeyboardInterrupt. Needs no GIL.
/// `keywords` (may be empty) are given to each call of a function (`plan(telemetry, **kw)`)
/// or to the class when making an instance (`Planner(**kw)`).
[[nodiscard]] planner::PolicyFactory callable_policy_factory(
    SharedObject callable, std::string label, std::shared_ptr<DriveInterruption> stops = nullptr,
    std::map<std::string, double> keywords = {});

/// Why `callable` cannot take these keyword arguments (a function after the telemetry, a
/// class when making an instance), as Python's inspect.signature says; "" when it can, or
/// when Python cannot tell (a builtin without a signature). Needs the GIL.
[[nodiscard]] std::string keyword_problem(const pybind11::object& callable,
                                          const std::vector<std::string>& names);

}  // namespace overtake::python
