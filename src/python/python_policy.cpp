// `--policy-py MODULE:FUNCTION`: the interpreter embedded in the binary, started once when a
// Python planner is first loaded. Inside a Python process (the `overtake` module) the running
// interpreter is used instead.
#include "overtake/python/python_policy.hpp"

#include <pybind11/embed.h>

#include <cctype>
#include <filesystem>
#include <mutex>
#include <optional>
#include <system_error>

#include "overtake/core/hash.hpp"
#include "overtake/python/bridge.hpp"

namespace overtake::python {
namespace py = pybind11;

namespace {

// Starts the interpreter (once), puts the current directory first on sys.path (PYTHONPATH
// comes next, as Python reads it) and the build's Python package last, and releases the GIL: every
// call into Python takes it (gil_scoped_acquire), from whichever thread runs the planner. The
// interpreter lives until the process exits (it is never finalized: planners may still hold objects
// at exit).
void ensure_interpreter() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (Py_IsInitialized() != 0) return;  // inside Python: the module's interpreter
    // No signal handlers: Ctrl-C stays the run's (it stops the run, not the interpreter); a
    // planner still running then gets its KeyboardInterrupt from Policy::interrupt().
    PyConfig config;
    PyConfig_InitIsolatedConfig(&config);
    config.isolated = 0;
    config.use_environment = 1;  // PYTHONPATH, PYTHONHOME and the rest are read as Python does
    config.install_signal_handlers = 0;
    // The interpreter this binary was built against finds its own standard library and
    // site-packages; without a program name Python would take the first python3 on PATH
    // (a pyenv, conda or virtual environment's: another version, other packages, numpy
    // missing). PYTHONHOME still chooses another.
    const PyStatus named =
        PyConfig_SetBytesString(&config, &config.program_name, OVERTAKE_PYTHON_EXECUTABLE);
    if (PyStatus_Exception(named) != 0) {
      PyConfig_Clear(&config);
      throw std::runtime_error("cannot start Python: out of memory");
    }
    py::initialize_interpreter(&config);
    try {
      const py::object path = py::module_::import("sys").attr("path");
      path.attr("insert")(0, std::filesystem::current_path().string());
      // Last, the package built beside this binary: a planner's `import overtake` (a learned
      // policy's overtake.Driver) finds the module of this very build when nothing on the path
      // before it (PYTHONPATH, an installed package) provides one.
      std::error_code ec;
      if (std::filesystem::is_directory(OVERTAKE_PYTHON_PACKAGE_DIR, ec)) {
        path.attr("append")(OVERTAKE_PYTHON_PACKAGE_DIR);
      }
    } catch (const py::error_already_set&) {  // sys.path stays as it is
    }
    (void)py::detail::get_internals();  // pybind11's per-thread state, made with the GIL held
    (void)PyEval_SaveThread();          // the GIL is released for good on this thread
  });
}

// A module name of its own for a planner file, from its absolute path: two planner.py in two
// folders are two modules, and neither takes the name of a module a planner might import.
std::string module_name_of(const std::filesystem::path& file) {
  std::string stem = file.stem().string();
  for (char& c : stem) {
    if (std::isalnum(static_cast<unsigned char>(c)) == 0) c = '_';
  }
  return "overtake_planner_" + stem + "_" + core::hex64(core::fnv1a64(file.string())).substr(0, 12);
}

// Removes from sys.path the entry `entry` (that very object, wherever the module's code may
// have moved it); an entry the module removed itself is left so.
void remove_path_entry(const py::object& entry) {
  const py::list path = py::module_::import("sys").attr("path");
  for (std::size_t i = 0; i < path.size(); ++i) {
    if (path[i].ptr() == entry.ptr()) {
      (void)path.attr("pop")(i);
      return;
    }
  }
}

// Runs the planner file as the module `name` (or takes the module already loaded from it).
// Its folder is first on sys.path while it runs, for the imports of the modules beside it,
// and no longer afterwards: it must not decide what later imports of other planners find.
// Needs the GIL.
py::object load_file_module(const std::filesystem::path& file, const std::string& name) {
  const py::dict modules = py::module_::import("sys").attr("modules");
  if (modules.contains(name)) return modules[name.c_str()];
  // The loader named explicitly: a planner file need not end in .py.
  const py::object loader =
      py::module_::import("importlib.machinery").attr("SourceFileLoader")(name, file.string());
  const py::module_ util = py::module_::import("importlib.util");
  const py::object spec =
      util.attr("spec_from_file_location")(name, file.string(), py::arg("loader") = loader);
  const py::object module = util.attr("module_from_spec")(spec);
  modules[name.c_str()] = module;  // before it runs, as an import does (dataclasses need it)
  const py::str folder(file.parent_path().string());
  py::module_::import("sys").attr("path").attr("insert")(0, folder);
  try {
    loader.attr("exec_module")(module);
  } catch (const py::error_already_set&) {
    remove_path_entry(folder);
    (void)modules.attr("pop")(name, py::none());
    throw;
  }
  remove_path_entry(folder);
  return module;
}

}  // namespace

LoadedPython load_python_policy(const std::string& spec) {
  const std::size_t colon = spec.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == spec.size()) {
    throw PythonError("'" + spec + "' is not MODULE:FUNCTION (e.g. planner:plan)");
  }
  const std::string target = spec.substr(0, colon);
  const std::string function_name = spec.substr(colon + 1);
  // A file (planners/mine.py:plan), loaded as a module named after its path; else a module,
  // imported from the current directory or PYTHONPATH.
  std::optional<std::filesystem::path> file;
  std::string module_name = target;
  if (target.ends_with(".py") || target.find('/') != std::string::npos) {
    if (!std::filesystem::is_regular_file(target)) {
      throw PythonError("no Python file '" + target + "' (from '" + spec + "')");
    }
    std::error_code error;
    file = std::filesystem::weakly_canonical(std::filesystem::absolute(target), error);
    if (error) file = std::filesystem::absolute(target);
    module_name = module_name_of(*file);
  }
  ensure_interpreter();
  SharedObject callable;
  {
    py::gil_scoped_acquire gil;
    py::object module;
    try {
      module =
          file ? load_file_module(*file, module_name) : py::module_::import(module_name.c_str());
    } catch (const py::error_already_set& e) {
      throw PythonError((file ? "cannot load the file '" + target + "': "
                              : "cannot import the module '" + module_name + "': ") +
                        describe(e));
    }
    const std::string what =
        file ? "the file '" + target + "'" : "the module '" + module_name + "'";
    if (!py::hasattr(module, function_name.c_str())) {
      throw PythonError(what + " (" +
                        std::string(py::str(py::getattr(module, "__file__", py::str("?")))) +
                        ") has no '" + function_name + "'");
    }
    py::object f = module.attr(function_name.c_str());
    if (PyCallable_Check(f.ptr()) == 0) {
      throw PythonError((file ? target : module_name) + "." + function_name + " is a " +
                        std::string(py::str(py::type::handle_of(f).attr("__name__"))) +
                        ", not callable");
    }
    callable = share(std::move(f));
  }
  LoadedPython loaded;
  // Named after the file's stem, or the module (its last part): planner.py:plan and
  // pkg.planner:plan are both "planner".
  loaded.name = file ? std::filesystem::path(target).stem().string()
                     : module_name.substr(module_name.rfind('.') + 1);
  loaded.make = callable_policy_factory(callable, spec);
  loaded.with_keywords = [callable, spec](const std::map<std::string, double>& keywords) {
    std::vector<std::string> names;
    for (const auto& [name, value] : keywords) names.push_back(name);
    std::string problem;
    {
      py::gil_scoped_acquire gil;
      problem = keyword_problem(*callable, names);
    }
    if (!problem.empty()) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      throw PythonError(spec + " cannot take the keyword arguments " + list + ": " + problem);
    }
    return callable_policy_factory(callable, spec, nullptr, keywords);
  };
  return loaded;
}

}  // namespace overtake::python
