// `--policy-py MODULE:FUNCTION`: the interpreter embedded in the binary, started once when a
// Python planner is first loaded. Inside a Python process (the `overtake` module) the running
// interpreter is used instead.
#include "overtake/python/python_policy.hpp"

#include <pybind11/embed.h>

#include <filesystem>
#include <mutex>

#include "overtake/python/bridge.hpp"

namespace overtake::python {
namespace py = pybind11;

namespace {

// Starts the interpreter (once), puts the current directory first on sys.path (PYTHONPATH
// comes next, as Python reads it), and releases the GIL: every call into Python takes it
// (gil_scoped_acquire), from whichever thread runs the planner. The interpreter lives until
// the process exits (it is never finalized: planners may still hold objects at exit).
void ensure_interpreter() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (Py_IsInitialized() != 0) return;  // inside Python: the module's interpreter
    // No signal handlers: Ctrl-C stays the run's (it stops the run, not the interpreter).
    py::initialize_interpreter(/*init_signal_handlers=*/false);
    try {
      py::module_::import("sys").attr("path").attr("insert")(
          0, std::filesystem::current_path().string());
    } catch (const py::error_already_set&) {  // sys.path stays as it is
    }
    (void)py::detail::get_internals();  // pybind11's per-thread state, made with the GIL held
    (void)PyEval_SaveThread();          // the GIL is released for good on this thread
  });
}

}  // namespace

LoadedPython load_python_policy(const std::string& spec) {
  const std::size_t colon = spec.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == spec.size()) {
    throw PythonError("'" + spec + "' is not MODULE:FUNCTION (e.g. planner:plan)");
  }
  std::string module_name = spec.substr(0, colon);
  const std::string function_name = spec.substr(colon + 1);
  // A file (planners/mine.py:plan): its folder goes first on sys.path, its stem is the module.
  std::string folder;
  if (module_name.ends_with(".py") || module_name.find('/') != std::string::npos) {
    const std::filesystem::path file(module_name);
    if (!std::filesystem::is_regular_file(file)) {
      throw PythonError("no Python file '" + module_name + "' (from '" + spec + "')");
    }
    folder = std::filesystem::absolute(file).parent_path().string();
    module_name = file.stem().string();
  }
  ensure_interpreter();
  SharedObject callable;
  {
    py::gil_scoped_acquire gil;
    if (!folder.empty()) py::module_::import("sys").attr("path").attr("insert")(0, folder);
    py::module_ module;
    try {
      module = py::module_::import(module_name.c_str());
    } catch (const py::error_already_set& e) {
      throw PythonError("cannot import the module '" + module_name + "': " + describe(e));
    }
    if (!py::hasattr(module, function_name.c_str())) {
      throw PythonError("the module '" + module_name + "' (" +
                        std::string(py::str(py::getattr(module, "__file__", py::str("?")))) +
                        ") has no '" + function_name + "'");
    }
    py::object f = module.attr(function_name.c_str());
    if (PyCallable_Check(f.ptr()) == 0) {
      throw PythonError(module_name + "." + function_name + " is a " +
                        std::string(py::str(py::type::handle_of(f).attr("__name__"))) +
                        ", not callable");
    }
    callable = share(std::move(f));
  }
  LoadedPython loaded;
  // Named after the module (its last part): planner.py:plan is "planner".
  loaded.name = module_name.substr(module_name.rfind('.') + 1);
  loaded.make = callable_policy_factory(std::move(callable), spec);
  return loaded;
}

}  // namespace overtake::python
