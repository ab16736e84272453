#include "overtake/python/bridge.hpp"

#include <pybind11/numpy.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <filesystem>
#include <system_error>
#include <thread>
#include <utility>

#include "overtake/core/units.hpp"
#include "overtake/core/wire_number.hpp"
#include "overtake/python/python_policy.hpp"

namespace overtake::python {
namespace py = pybind11;

namespace {

constexpr std::size_t kFusionColumns = 7;  // [id, x, y, vx, vy, s, d]

// Whether numpy can be imported: 0 not asked yet, 1 yes, 2 no. An atomic, not a static
// local: an import may release the GIL, and another thread then waiting on a static local's
// guard while holding the GIL would deadlock.
std::atomic<int> numpy_state{0};

bool have_numpy() {
  int state = numpy_state.load(std::memory_order_relaxed);
  if (state == 0) {
    try {
      (void)py::module_::import("numpy");
      state = 1;
    } catch (const py::error_already_set&) {
      state = 2;
    }
    numpy_state.store(state, std::memory_order_relaxed);
  }
  return state == 1;
}

// A number as the original prints it and a planner parses it.
double wire(double v) {
  return core::wire_round(v);
}

std::string type_name(py::handle h) {
  return py::str(py::type::handle_of(h).attr("__name__"));
}

double finite(py::handle item, const std::string& what) {
  const double v = PyFloat_AsDouble(item.ptr());
  if (v == -1.0 && PyErr_Occurred()) {
    PyErr_Clear();
    throw PythonError(what + " is " + type_name(item) + ", not a number");
  }
  if (!std::isfinite(v))
    throw PythonError(what + " is not a finite number (" + std::to_string(v) + ")");
  return v;
}

// The numbers of a 1-D sequence (a list, a tuple, a numpy array).
std::vector<double> numbers(py::handle seq, const std::string& what, std::size_t max_size) {
  if (have_numpy() && py::isinstance<py::array>(seq)) {
    const auto a = py::array_t<double, py::array::forcecast>::ensure(seq);
    if (!a) throw PythonError(what + " is an array of non-numbers");
    if (a.ndim() != 1)
      throw PythonError(what + " has " + std::to_string(a.ndim()) + " dimensions, not 1");
    const auto n = static_cast<std::size_t>(a.shape(0));
    if (n > max_size) {
      throw PythonError(what + " has " + std::to_string(n) + " points, more than the limit of " +
                        std::to_string(max_size));
    }
    std::vector<double> out(n);
    const auto view = a.unchecked<1>();
    for (std::size_t i = 0; i < n; ++i) {
      out[i] = view(static_cast<py::ssize_t>(i));
      if (!std::isfinite(out[i])) {
        throw PythonError(what + "[" + std::to_string(i) + "] is not a finite number (" +
                          std::to_string(out[i]) + ")");
      }
    }
    return out;
  }
  if (!py::isinstance<py::sequence>(seq) || py::isinstance<py::str>(seq)) {
    throw PythonError(what + " is " + type_name(seq) + ", not a list of numbers");
  }
  const auto s = py::reinterpret_borrow<py::sequence>(seq);
  const std::size_t n = s.size();
  if (n > max_size) {
    throw PythonError(what + " has " + std::to_string(n) + " points, more than the limit of " +
                      std::to_string(max_size));
  }
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i)
    out[i] = finite(py::object(s[i]), what + "[" + std::to_string(i) + "]");
  return out;
}

py::object member(py::handle dict, const char* key) {
  if (!py::isinstance<py::dict>(dict)) throw PythonError("the telemetry is not a dict");
  const auto d = py::reinterpret_borrow<py::dict>(dict);
  if (!d.contains(key)) throw PythonError(std::string("the telemetry has no '") + key + "'");
  return d[key];
}

double number_member(py::handle dict, const char* key) {
  return finite(member(dict, key), std::string("'") + key + "'");
}

}  // namespace

py::dict telemetry_to_dict(const core::Telemetry& t) {
  py::dict d;
  d["x"] = wire(t.ego.position.x);
  d["y"] = wire(t.ego.position.y);
  d["yaw"] = wire(core::rad_to_deg(t.ego.yaw_rad));
  d["speed"] = wire(core::mps_to_mph(t.ego.speed_mps));
  d["s"] = wire(t.ego.s_m);
  d["d"] = wire(t.ego.d_m);
  const std::size_t n = t.previous_path.size();
  py::list px(n);
  py::list py_(n);
  for (std::size_t i = 0; i < n; ++i) {
    px[i] = wire(t.previous_path[i].x);
    py_[i] = wire(t.previous_path[i].y);
  }
  d["previous_path_x"] = px;
  d["previous_path_y"] = py_;
  d["end_path_s"] = wire(t.end_path.s_m);
  d["end_path_d"] = wire(t.end_path.d_m);
  py::list fusion(t.cars.size());
  for (std::size_t i = 0; i < t.cars.size(); ++i) {
    const core::CarObservation& c = t.cars[i];
    py::list row(kFusionColumns);
    row[0] = c.id;
    row[1] = wire(c.position.x);
    row[2] = wire(c.position.y);
    row[3] = wire(c.velocity_mps.x);
    row[4] = wire(c.velocity_mps.y);
    row[5] = wire(c.s_m);
    row[6] = wire(c.d_m);
    fusion[i] = row;
  }
  d["sensor_fusion"] = fusion;
  if (have_numpy()) {
    py::array_t<double> path({static_cast<py::ssize_t>(n), py::ssize_t{2}});
    auto pm = path.mutable_unchecked<2>();
    for (std::size_t i = 0; i < n; ++i) {
      const auto r = static_cast<py::ssize_t>(i);
      pm(r, 0) = wire(t.previous_path[i].x);
      pm(r, 1) = wire(t.previous_path[i].y);
    }
    d["previous_path_array"] = path;
    py::array_t<double> cars(
        {static_cast<py::ssize_t>(t.cars.size()), static_cast<py::ssize_t>(kFusionColumns)});
    auto cm = cars.mutable_unchecked<2>();
    for (std::size_t i = 0; i < t.cars.size(); ++i) {
      const core::CarObservation& c = t.cars[i];
      const auto r = static_cast<py::ssize_t>(i);
      const double row[kFusionColumns] = {
          static_cast<double>(c.id), c.position.x, c.position.y, c.velocity_mps.x,
          c.velocity_mps.y,          c.s_m,        c.d_m};
      for (std::size_t k = 0; k < kFusionColumns; ++k) {
        cm(r, static_cast<py::ssize_t>(k)) = k == 0 ? row[k] : wire(row[k]);
      }
    }
    d["sensor_fusion_array"] = cars;
  }
  return d;
}

core::Telemetry telemetry_from_dict(py::handle dict) {
  core::Telemetry t;
  t.ego.position = {number_member(dict, "x"), number_member(dict, "y")};
  t.ego.yaw_rad = core::deg_to_rad(number_member(dict, "yaw"));
  t.ego.speed_mps = core::mph_to_mps(number_member(dict, "speed"));
  t.ego.s_m = number_member(dict, "s");
  t.ego.d_m = number_member(dict, "d");
  const auto xs = numbers(member(dict, "previous_path_x"), "'previous_path_x'", kMaxPathPoints);
  const auto ys = numbers(member(dict, "previous_path_y"), "'previous_path_y'", kMaxPathPoints);
  if (xs.size() != ys.size()) {
    throw PythonError("'previous_path_x' has " + std::to_string(xs.size()) +
                      " points but 'previous_path_y' has " + std::to_string(ys.size()));
  }
  t.previous_path.resize(xs.size());
  for (std::size_t i = 0; i < xs.size(); ++i) t.previous_path[i] = {xs[i], ys[i]};
  t.end_path = {number_member(dict, "end_path_s"), number_member(dict, "end_path_d")};
  const py::object fusion = member(dict, "sensor_fusion");
  if (!py::isinstance<py::sequence>(fusion)) throw PythonError("'sensor_fusion' is not a list");
  const auto rows = py::reinterpret_borrow<py::sequence>(fusion);
  t.cars.resize(rows.size());
  for (std::size_t i = 0; i < t.cars.size(); ++i) {
    const std::string where = "'sensor_fusion'[" + std::to_string(i) + "]";
    const auto v = numbers(py::object(rows[i]), where, kFusionColumns);
    if (v.size() != kFusionColumns) {
      throw PythonError(where + " has " + std::to_string(v.size()) +
                        " values, expected 7 [id,x,y,vx,vy,s,d]");
    }
    if (v[0] != std::floor(v[0])) throw PythonError(where + ": the id is not an integer");
    const double row[7] = {v[0], v[1], v[2], v[3], v[4], v[5], v[6]};
    t.cars[i] = core::car_from_row(row);
  }
  return t;
}

std::vector<core::Vec2> path_from_python(py::handle answer) {
  const bool pair = (py::isinstance<py::tuple>(answer) || py::isinstance<py::list>(answer) ||
                     (have_numpy() && py::isinstance<py::array>(answer))) &&
                    py::len(answer) == 2;
  if (!pair) {
    throw PythonError(
        "the planner answered " + type_name(answer) +
        (answer.is_none() ? "" : " of length " + std::to_string(py::len_hint(answer))) +
        ", not a pair (path_x, path_y)");
  }
  const auto xs = numbers(py::object(answer[py::int_(0)]), "path_x", kMaxPathPoints);
  const auto ys = numbers(py::object(answer[py::int_(1)]), "path_y", kMaxPathPoints);
  if (xs.size() != ys.size()) {
    throw PythonError("path_x has " + std::to_string(xs.size()) + " points but path_y has " +
                      std::to_string(ys.size()));
  }
  std::vector<core::Vec2> path(xs.size());
  for (std::size_t i = 0; i < xs.size(); ++i) path[i] = {xs[i], ys[i]};
  return path;
}

namespace {

// A Python exception in two parts: "Type: message", and where it was raised, "file, line N,
// in function" (empty when it has no traceback).
struct Described {
  std::string what = "an exception";
  std::string where;
};

Described described(const py::error_already_set& e) {
  Described out;
  try {
    out.what = py::str(e.type().attr("__name__"));
    const std::string message = py::str(e.value());
    if (!message.empty()) out.what += ": " + message;
    if (e.trace()) {
      const py::list frames = py::module_::import("traceback").attr("extract_tb")(e.trace());
      if (!frames.empty()) {
        const py::object last = frames[frames.size() - 1];
        const std::string file = py::str(last.attr("filename"));
        out.where = std::filesystem::path(file).filename().string() + ", line " +
                    std::string(py::str(last.attr("lineno"))) + ", in " +
                    std::string(py::str(last.attr("name")));
      }
    }
  } catch (const py::error_already_set&) {  // a message that cannot be printed: keep what we have
  }
  return out;
}

}  // namespace

std::string describe(const py::error_already_set& e) {
  const Described d = described(e);
  return d.where.empty() ? d.what : d.what + " (" + d.where + ")";
}

SharedObject share(py::object object) {
  return SharedObject(new py::object(std::move(object)), [](py::object* p) {
    if (Py_IsInitialized() != 0) {
      py::gil_scoped_acquire gil;
      delete p;
    } else {
      (void)p->release();  // the interpreter is gone: nothing to release
      delete p;
    }
  });
}

bool DriveInterruption::stops_the_drive(const py::error_already_set& e) {
  return e.matches(PyExc_KeyboardInterrupt) || e.matches(PyExc_SystemExit);
}

void DriveInterruption::keep(const py::error_already_set& e) {
  {
    const std::lock_guard lock(mutex_);
    if (!kept_) kept_ = e;
  }
  stop_.store(true);
}

void DriveInterruption::raise_if_kept() {
  std::optional<py::error_already_set> kept;
  {
    const std::lock_guard lock(mutex_);
    kept = kept_;
  }
  if (kept) throw *kept;
}

namespace {

// How long interrupt() waits for the exception to be set before it returns anyway.
constexpr auto kInterruptWait = std::chrono::milliseconds(200);

// A policy's Python call as another thread sees it, to interrupt it. The policy and the
// threads that deliver an interruption share it (a delivery may outlive the policy). Lock
// order: the GIL before `mutex` (whoever holds `mutex` never waits for the GIL).
struct CallWatch {
  std::mutex mutex;
  std::condition_variable delivered;
  bool running = false;                         // a call runs now
  unsigned long thread = 0;                     // the Python ident of the thread that runs it
  std::optional<core::PlanInterruption> asked;  // what the running call was asked to stop for
  bool delivering = false;                      // a delivery is on its way
};

// Sets the exception in the running call, on a thread of its own: taking the GIL may wait for
// as long as the planner runs C code that holds it, and the watchdog that asked must not
// wait that long. The exception is asynchronous: Python raises it at the planner's next
// bytecode. A planner blocked in C (time.sleep, a long numpy call, a socket) runs none and
// is not stopped by it until the C call returns; the watchdog then ends the process.
void deliver(const std::shared_ptr<CallWatch>& watch) {
  const PyGILState_STATE gil = PyGILState_Ensure();
  {
    const std::lock_guard lock(watch->mutex);
    // Only into the call that was asked (a new call starts with `asked` empty).
    if (watch->running && watch->asked) {
      PyObject* type = *watch->asked == core::PlanInterruption::user_stop ? PyExc_KeyboardInterrupt
                                                                          : PyExc_TimeoutError;
      (void)PyThreadState_SetAsyncExc(watch->thread, type);
    }
    watch->delivering = false;
  }
  watch->delivered.notify_all();
  PyGILState_Release(gil);
}

// A Python callable as a policy.
class CallablePolicy final : public planner::Policy {
 public:
  CallablePolicy(SharedObject callable, std::string label, std::shared_ptr<DriveInterruption> stops)
      : callable_(std::move(callable)), label_(std::move(label)), stops_(std::move(stops)) {}

  core::PlanResult plan(const core::Telemetry& telemetry) override {
    std::string failure;
    {
      py::gil_scoped_acquire gil;
      std::optional<core::PlanInterruption> asked;
      try {
        const py::object answer = call(telemetry_to_dict(telemetry), asked);
        // A Python planner answers points only: how it found them is not for overtake to say.
        core::PlanResult result = core::normal_plan(path_from_python(answer));
        result.status_known = false;
        return result;
      } catch (const py::error_already_set& e) {
        if (stops_ && DriveInterruption::stops_the_drive(e)) stops_->keep(e);
        failure = failure_text(e, asked);
      } catch (const std::exception& e) {
        failure = "Python planner " + label_ + ": " + e.what();
      }
    }
    throw PythonError(failure);
  }

  bool interrupt(core::PlanInterruption why) noexcept override {
    if (Py_IsInitialized() == 0) return false;
    try {
      std::unique_lock lock(watch_->mutex);
      if (!watch_->running) return true;  // between calls: nothing to stop
      // Ctrl-C wins over a timeout: the run is over either way, the user's word says why.
      if (!watch_->asked || why == core::PlanInterruption::user_stop) watch_->asked = why;
      if (!watch_->delivering) {
        watch_->delivering = true;
        try {
          std::thread([watch = watch_] { deliver(watch); }).detach();
        } catch (const std::system_error&) {  // no thread to be had
          watch_->delivering = false;
          return false;
        }
      }
      (void)watch_->delivered.wait_for(lock, kInterruptWait,
                                       [this] { return !watch_->delivering; });
      return true;
    } catch (const std::exception&) {  // a mutex that cannot be locked
      return false;
    }
  }

 private:
  // Calls the callable (with the GIL held) where interrupt() can reach it; `asked` is what the
  // call was asked to stop for, if anything.
  py::object call(const py::dict& telemetry, std::optional<core::PlanInterruption>& asked) {
    {
      const std::lock_guard lock(watch_->mutex);
      watch_->running = true;
      watch_->thread = PyThread_get_thread_ident();
      watch_->asked.reset();
    }
    try {
      py::object answer = (*callable_)(telemetry);
      asked = end_call();
      return answer;
    } catch (...) {
      asked = end_call();
      throw;
    }
  }

  std::optional<core::PlanInterruption> end_call() {
    std::optional<core::PlanInterruption> asked;
    unsigned long thread = 0;
    {
      const std::lock_guard lock(watch_->mutex);
      watch_->running = false;
      asked = watch_->asked;
      thread = watch_->thread;
    }
    // An exception set just as the call returned has not been raised yet: it would be at the
    // next bytecode this thread runs, in another call or another planner. Dropped here (no
    // delivery can set one now: it would need the GIL, which this thread holds).
    (void)PyThreadState_SetAsyncExc(thread, nullptr);
    return asked;
  }

  [[nodiscard]] std::string failure_text(const py::error_already_set& e,
                                         std::optional<core::PlanInterruption> asked) const {
    if (!asked) return "Python planner " + label_ + " raised " + describe(e);
    const Described d = described(e);
    const std::string how = *asked == core::PlanInterruption::timeout
                                ? " did not answer in time and was interrupted ("
                                : " was stopped by the user (";
    return "Python planner " + label_ + how + d.what + (d.where.empty() ? "" : " at " + d.where) +
           ")";
  }

  SharedObject callable_;
  std::string label_;
  std::shared_ptr<DriveInterruption> stops_;
  std::shared_ptr<CallWatch> watch_ = std::make_shared<CallWatch>();
};

}  // namespace

std::string keyword_problem(const py::object& callable, const std::vector<std::string>& names) {
  py::dict kw;
  for (const auto& n : names) kw[py::str(n)] = 0.0;
  py::object signature;
  try {
    signature = py::module_::import("inspect").attr("signature")(callable);
  } catch (const py::error_already_set&) {
    return {};  // no signature to read (a builtin): the call will say
  }
  try {
    if (PyType_Check(callable.ptr()) != 0) {
      signature.attr("bind_partial")(**kw);
    } else {
      signature.attr("bind_partial")(py::none(), **kw);
    }
  } catch (const py::error_already_set& e) {
    return described(e).what;
  }
  return {};
}

planner::PolicyFactory callable_policy_factory(SharedObject callable, std::string label,
                                               std::shared_ptr<DriveInterruption> stops,
                                               std::map<std::string, double> keywords) {
  return [callable = std::move(callable), label = std::move(label), stops = std::move(stops),
          keywords = std::move(keywords)](
             const core::ReferenceLine&,
             const planner::PlannerParams&) -> std::unique_ptr<planner::Policy> {
    SharedObject target = callable;
    {
      py::gil_scoped_acquire gil;
      py::dict kw;
      for (const auto& [name, value] : keywords) kw[py::str(name)] = value;
      if (PyType_Check(callable->ptr()) != 0) {  // a class: one instance per run
        try {
          target = share((*callable)(**kw));
        } catch (const py::error_already_set& e) {
          if (stops && DriveInterruption::stops_the_drive(e)) stops->keep(e);
          throw PythonError("Python planner " + label + ": making an instance raised " +
                            describe(e));
        }
      } else if (!keywords.empty()) {  // a function: the keywords join each call
        target = share(py::module_::import("functools").attr("partial")(*callable, **kw));
      }
    }
    return std::make_unique<CallablePolicy>(std::move(target), label, stops);
  };
}

}  // namespace overtake::python
