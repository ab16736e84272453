// The Python module `overtake._overtake` (wrapped by python/overtake/__init__.py): the world
// stepped from Python (World), whole drives with a Python callable as the planner (drive),
// the built-in policies as callables (builtin_policy), and a bench folder's evaluation
// (bench_summary, compare). An edge like the command line: it
// drives the world through the same stepper and the same drive as `overtake drive`.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cctype>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "convert.hpp"
#include "learn.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/batch/pool.hpp"
#include "overtake/batch/risk.hpp"
#include "overtake/core/map.hpp"
#include "overtake/eval/summary.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/python/bridge.hpp"
#include "overtake/python/python_policy.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "overtake/sim/run.hpp"
#include "overtake/sim/world.hpp"

namespace overtake::pybind {
namespace {

namespace py = pybind11;
using Clock = std::chrono::steady_clock;

// Options of a drive from keyword arguments, as `overtake drive` takes them from flags.
run::DriveOptions drive_options(const std::optional<std::string>& map, std::uint64_t seed,
                                const std::string& traffic,
                                const std::optional<std::string>& config,
                                const std::optional<int>& steps_per_call, double minutes) {
  run::DriveOptions o;
  if (map) o.map = *map;
  if (config) o.config = *config;
  o.seed = seed;
  o.traffic = traffic;
  o.minutes = minutes;
  o.steps_per_call = steps_per_call.value_or(0);
  if (steps_per_call && *steps_per_call <= 0) {
    throw base::UsageError("steps_per_call must be between 1 and 1000 (got " +
                           std::to_string(*steps_per_call) + ")");
  }
  return o;
}

// A catalog with one Python planner of that name, for the report's config.
std::shared_ptr<planners::PlannerCatalog> catalog_with(const std::string& name, std::string source,
                                                       planner::PolicyFactory make) {
  auto catalog = std::make_shared<planners::PlannerCatalog>();
  planners::PlannerEntry e;
  e.name = name;
  e.kind = planners::PlannerKind::python;
  e.source = std::move(source);
  e.make = std::move(make);
  catalog->add(std::move(e), "name");
  return catalog;
}

// One call at a time into an object that is not thread-safe. A second call while one runs
// (from another thread, or from Python code the first one runs: a path's __float__, a
// finalizer) would step or free the world under the first: it gets a RuntimeError instead.
// The flag is taken and left with the GIL held.
class OneCallAtATime {
 public:
  OneCallAtATime(bool& busy, const char* what) : busy_(busy) {
    if (busy_) {
      throw std::runtime_error(
          std::string(what) +
          ": another call of this object has not returned yet (from another thread?); it is "
          "for one thread at a time: make one per thread, or lock around it");
    }
    busy_ = true;
  }
  ~OneCallAtATime() { busy_ = false; }
  OneCallAtATime(const OneCallAtATime&) = delete;
  OneCallAtATime& operator=(const OneCallAtATime&) = delete;

 private:
  bool& busy_;
};

// ---- World -------------------------------------------------------------------------------

// The world stepped from Python: reset, then step with a path per reply, as `drive` does.
class World {
 public:
  World(const std::optional<std::string>& map, std::uint64_t seed, const std::string& traffic,
        const std::optional<std::string>& config, const std::optional<int>& steps_per_call,
        double minutes, const std::string& name) {
    run::DriveOptions o = drive_options(map, seed, traffic, config, steps_per_call, minutes);
    o.policy = name;
    o.planners = catalog_with(name, "overtake.World", {});
    run::validate_drive_options(o);
    inputs_ = run::load_drive_inputs(o);
  }

  py::dict reset(const std::optional<std::uint64_t>& seed) {
    const OneCallAtATime one(busy_, "World.reset()");
    if (seed) inputs_.options.seed = *seed;
    const run::DriveOptions& o = inputs_.options;
    stepper_.reset();
    const run::Track& track = *inputs_.track;
    world_ = std::make_unique<sim::World>(track.map, track.line, inputs_.config.world,
                                          *sim::parse_traffic_profile(o.traffic), o.seed);
    provenance_ = run::drive_provenance(track, inputs_.config, o, nullptr);
    sim::RunOptions run;
    run.duration_s = o.minutes * 60.0;
    if (o.steps_per_call > 0) run.steps_per_call = o.steps_per_call;
    run.seed = o.seed;
    // The planner's time is Python's, between a telemetry given and its path taken back.
    run.clock = sim::CycleClock::round_trip;
    stepper_ = std::make_unique<sim::Stepper>(*world_, run);
    incidents_ = py::list();
    return telemetry_now();
  }

  py::dict telemetry() {
    const OneCallAtATime one(busy_, "World.telemetry()");
    return telemetry_now();
  }

  // The GIL stays held while the world steps (a call is a few microseconds of C++), so that
  // no other thread runs Python, and none can reach the world, in the meantime.
  py::tuple step(py::handle path_x, py::handle path_y) {
    const OneCallAtATime one(busy_, "World.step()");
    sim::Stepper& s = stepper();
    if (s.finished()) throw std::runtime_error("the run is over (info['done']); call reset()");
    const double wall_us =
        std::chrono::duration<double, std::micro>(Clock::now() - given_at_).count();
    const std::size_t before = s.scorecard().referee().incidents().size();
    const long steps_before = world_->steps();
    try {
      core::PlanResult plan =
          core::normal_plan(python::path_from_python(py::make_tuple(path_x, path_y)));
      plan.status_known = false;  // points only: how they were found is the caller's
      s.apply(std::move(plan), wall_us, wall_us);
      s.step_one_call();
    } catch (const python::PythonError& e) {
      s.end(sim::RunEnd::planner_failed, std::string("Python planner: ") + e.what());
    }
    py::dict out = info_since(before);
    out["steps_this_call"] = world_->steps() - steps_before;
    return py::make_tuple(telemetry_now(), out);
  }

  py::object report() const {
    const OneCallAtATime one(busy_, "World.report()");
    return to_python(run::report_to_json(stepper().report(), provenance_));
  }

  [[nodiscard]] bool done() const { return stepper().finished(); }
  [[nodiscard]] double time_s() const { return world_ ? world_->time_s() : 0.0; }
  [[nodiscard]] long steps() const { return world_ ? world_->steps() : 0; }
  [[nodiscard]] double step_s() const { return inputs_.config.world.step_s; }

 private:
  py::dict telemetry_now() {
    const sim::Stepper& s = stepper();
    py::dict d = python::telemetry_to_dict(s.telemetry());
    given_at_ = Clock::now();
    return d;
  }

  py::dict info_since(std::size_t incidents_before) {
    const sim::Stepper& s = stepper();
    const sim::Referee& referee = s.scorecard().referee();
    const auto& all = referee.incidents();
    py::list fresh;
    for (std::size_t i = incidents_before; i < all.size(); ++i) {
      fresh.append(to_python(run::incident_to_json(all[i])));
    }
    for (const auto& i : fresh) incidents_.append(i);
    py::dict counts;
    const auto n = referee.counts();
    for (std::size_t t = 0; t < sim::kIncidentTypeCount; ++t) {
      counts[py::str(std::string(sim::to_string(static_cast<sim::IncidentType>(t))))] = n[t];
    }
    const sim::RunReport r = s.finished() ? s.report() : sim::RunReport{};
    py::dict out;
    out["time_s"] = world_->time_s();
    out["steps"] = world_->steps();
    out["distance_m"] = referee.distance_m();
    out["incident_counts"] = counts;
    out["incidents"] = incidents_.attr("copy")();
    out["new_incidents"] = fresh;
    out["done"] = s.finished();
    out["end"] = s.finished() ? std::string(sim::to_string(r.outcome.end)) : std::string("running");
    const std::string early = s.finished() ? sim::ended_early_text(r.outcome) : std::string();
    out["ended_early"] = early.empty() ? py::object(py::none()) : py::object(py::str(early));
    return out;
  }

  sim::Stepper& stepper() const {
    if (!stepper_) throw std::runtime_error("call reset() first");
    return *stepper_;
  }

  run::DriveInputs inputs_;
  run::RunProvenance provenance_;
  std::unique_ptr<sim::World> world_;
  std::unique_ptr<sim::Stepper> stepper_;  // refers to world_: reset before it
  py::list incidents_;
  Clock::time_point given_at_ = Clock::now();
  mutable bool busy_ = false;  // a call runs (OneCallAtATime)
};

// ---- built-in policies as callables --------------------------------------------------------

class BuiltinPolicy {
 public:
  BuiltinPolicy(const std::string& name, const std::optional<std::string>& map,
                const std::optional<std::string>& config)
      : name_(name),
        config_(run::load_config(config ? std::optional<std::filesystem::path>(*config)
                                        : std::nullopt)),
        track_(run::load_track(map ? std::optional<std::filesystem::path>(*map) : std::nullopt)) {
    policy_ = planner::make_policy(name, track_->line, config_.planner);
    if (!policy_) {
      throw base::UsageError(planner::unknown_policy_text(name));
    }
  }

  py::tuple call(py::handle telemetry) {
    const OneCallAtATime one(busy_, "BuiltinPolicy.__call__()");
    const core::Telemetry t = python::telemetry_from_dict(telemetry);
    core::PlanResult plan;
    {
      // Without the GIL: a planner's cycle may take milliseconds, other Python threads run
      // meanwhile (and cannot call this policy: `busy_`).
      py::gil_scoped_release nogil;
      plan = policy_->plan(t);
    }
    status_ = std::string(core::to_string(plan.status));
    return path_to_python(plan.path);
  }

  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] const std::string& status() const { return status_; }

 private:
  std::string name_;
  run::Config config_;
  std::shared_ptr<const run::Track> track_;
  std::unique_ptr<planner::Policy> policy_;  // refers to track_: declared after it
  std::string status_ = "normal";
  bool busy_ = false;  // a call runs (OneCallAtATime)
};

// ---- whole drives --------------------------------------------------------------------------

bool usable_name(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  for (const char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.')
      return false;
  }
  return true;
}

py::object drive(const py::object& policy, const std::optional<std::string>& map,
                 std::uint64_t seed, const std::string& traffic, double minutes,
                 const std::optional<std::string>& config, const std::optional<int>& steps_per_call,
                 const std::optional<std::string>& name) {
  run::DriveOptions o = drive_options(map, seed, traffic, config, steps_per_call, minutes);
  // Ctrl-C (or a planner's KeyboardInterrupt, SystemExit) stops the run and is raised again
  // here: a loop over drives must end, not go on with the next one.
  const auto stops = std::make_shared<python::DriveInterruption>();
  if (py::isinstance<py::str>(policy)) {
    o.policy = policy.cast<std::string>();
  } else if (PyCallable_Check(policy.ptr()) != 0) {
    std::string label = name.value_or("");
    if (label.empty()) {
      label = py::str(py::getattr(policy, "__name__", py::str("python")));
      if (!usable_name(label) || planners::PlannerCatalog().find(label)) label = "python";
    }
    const std::string source =
        std::string(py::str(py::getattr(policy, "__module__", py::str("?")))) + ":" +
        std::string(py::str(py::getattr(policy, "__qualname__", py::str("callable"))));
    o.planners = catalog_with(label, source,
                              python::callable_policy_factory(python::share(policy), label, stops));
    o.policy = label;
  } else {
    throw base::UsageError("policy must be a built-in policy's name or a callable");
  }
  // Python's signal handlers run only when the main thread runs bytecode, which a built-in
  // policy never does: the run looks for a signal Python has noted every 10 simulated
  // seconds (tens of milliseconds of a built-in policy's drive).
  const auto check_signals = [&stops](double /*t_s*/, double /*distance_m*/) {
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) stops->keep(py::error_already_set());
  };
  run::DriveResult result;
  try {
    py::gil_scoped_release nogil;
    result = run::drive(o, check_signals, stops->stop_flag());
  } catch (const std::exception&) {
    stops->raise_if_kept();  // what stopped it, rather than what it ended with
    throw;
  }
  stops->raise_if_kept();
  return to_python(run::report_to_json(result.report, result.provenance));
}

}  // namespace
}  // namespace overtake::pybind

PYBIND11_MODULE(_overtake, m) {
  namespace py = pybind11;
  using namespace overtake;
  using namespace overtake::pybind;
  m.doc() = "overtake: the headless highway simulator, stepped from Python";

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const base::UsageError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const run::ConfigError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const core::MapError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const python::PythonError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });

  py::class_<World>(m, "World")
      .def(py::init<const std::optional<std::string>&, std::uint64_t, const std::string&,
                    const std::optional<std::string>&, const std::optional<int>&, double,
                    const std::string&>(),
           py::arg("map") = py::none(), py::arg("seed") = 1, py::arg("traffic") = "faithful",
           py::arg("config") = py::none(), py::arg("steps_per_call") = py::none(),
           py::arg("minutes") = 30.0, py::arg("name") = "python")
      .def("reset", &World::reset, py::arg("seed") = py::none())
      .def("step", &World::step, py::arg("path_x"), py::arg("path_y"))
      .def("telemetry", &World::telemetry)
      .def("report", &World::report)
      .def_property_readonly("done", &World::done)
      .def_property_readonly("time_s", &World::time_s)
      .def_property_readonly("steps", &World::steps)
      .def_property_readonly("step_s", &World::step_s);

  py::class_<BuiltinPolicy>(m, "BuiltinPolicy")
      .def(py::init<const std::string&, const std::optional<std::string>&,
                    const std::optional<std::string>&>(),
           py::arg("name"), py::arg("map") = py::none(), py::arg("config") = py::none())
      .def("__call__", &BuiltinPolicy::call, py::arg("telemetry"))
      .def_property_readonly("name", &BuiltinPolicy::name)
      .def_property_readonly("status", &BuiltinPolicy::status);

  m.def("drive", &drive, py::arg("policy"), py::arg("map") = py::none(), py::arg("seed") = 1,
        py::arg("traffic") = "faithful", py::arg("minutes") = 30.0, py::arg("config") = py::none(),
        py::arg("steps_per_call") = py::none(), py::arg("name") = py::none());

  // A usage error (a --pair naming no policy, an unknown figure) is a ValueError; a folder
  // that holds no bench, or benches whose runs are not pairs, a RuntimeError.
  m.def(
      "compare",
      [](const std::string& before, const std::string& after, const std::vector<std::string>& pairs,
         const std::optional<std::string>& figures) {
        eval::CompareOptions o;
        try {
          for (const auto& p : pairs) o.pairs.push_back(batch::parse_policy_pair(p));
          if (figures) o.metrics = batch::parse_metric_list(*figures);
          return to_python(batch::compare_bench_folders(before, after, o));
        } catch (const base::UsageError& e) {
          throw py::value_error(e.what());
        }
      },
      py::arg("before"), py::arg("after"), py::arg("pairs") = std::vector<std::string>{},
      py::arg("figures") = py::none());

  m.def(
      "bench_summary",
      [](const std::string& folder) {
        std::vector<std::string> notes;
        const eval::BenchData b = batch::load_bench_for_compare(folder, notes);
        std::vector<std::string> traffic;
        if (b.manifest.contains("traffic") && b.manifest["traffic"].is_array()) {
          for (const auto& t : b.manifest["traffic"]) traffic.push_back(t.get<std::string>());
        }
        std::vector<std::string> policies;
        if (b.manifest.contains("policies") && b.manifest["policies"].is_array()) {
          for (const auto& p : b.manifest["policies"]) policies.push_back(p.get<std::string>());
        }
        const nlohmann::json rows = eval::summarize(b.runs, policies, traffic);
        const nlohmann::json pairs = eval::pair_policies(b.runs, policies, traffic);
        return to_python(
            nlohmann::json{{"rows", rows},
                           {"pairs", pairs},
                           {"verdicts", eval::verdict_method(eval::family_size(pairs))},
                           {"notes", notes}});
      },
      py::arg("folder"));

  // `overtake risk` (a built-in policy's name): the estimate's risk.json as a dict. Ctrl-C
  // stops it between cycles, keeping the finished runs in `out`, and raises KeyboardInterrupt.
  m.def(
      "risk",
      [](const std::string& policy, const std::string& event, const std::optional<std::string>& map,
         const std::string& traffic, double minutes, std::uint64_t first_seed, double rel_error,
         double budget_hours, std::size_t max_runs, const std::optional<std::string>& config,
         const std::optional<std::string>& params, int jobs, const std::string& out, bool resume,
         int scenarios) {
        batch::RiskSpec spec;
        try {
          spec.policy = policy;
          spec.event = batch::parse_risk_event(event);
          if (map && *map != "default") spec.map = *map;
          spec.traffic = traffic;
          spec.minutes = minutes;
          spec.first_seed = first_seed;
          spec.rel_error = rel_error;
          spec.budget_hours = budget_hours;
          spec.max_runs = max_runs;
          if (config) spec.config = *config;
          if (params) spec.params = *params;
          spec.jobs = jobs > 0 ? jobs : batch::default_jobs();
          spec.out = out;
          spec.resume = resume;
          spec.scenarios = scenarios;
          batch::check_risk_spec(spec);
        } catch (const base::UsageError& e) {
          throw py::value_error(e.what());
        }
        std::atomic<bool> stop{false};
        bool interrupted = false;
        batch::RiskOutcome o;
        {
          py::gil_scoped_release nogil;
          o = batch::run_risk(spec, &stop, [&](const batch::RiskProgress&) {
            py::gil_scoped_acquire gil;
            if (PyErr_CheckSignals() != 0) {
              stop = true;
              interrupted = true;
            }
          });
        }
        if (interrupted) throw py::error_already_set();
        return to_python(batch::risk_json(spec, o));
      },
      py::arg("policy") = "reference", py::arg("event") = "at-fault", py::arg("map") = py::none(),
      py::arg("traffic") = "faithful", py::arg("minutes") = 10.0, py::arg("first_seed") = 1,
      py::arg("rel_error") = 0.25, py::arg("budget_hours") = 20.0, py::arg("max_runs") = 100000,
      py::arg("config") = py::none(), py::arg("params") = py::none(), py::arg("jobs") = 0,
      py::arg("out") = "risk-out", py::arg("resume") = false, py::arg("scenarios") = 5);

  register_learning(m);

  m.def("policies", [] {
    py::dict d;
    for (const auto& p : planner::list_policies()) d[py::str(p.name)] = p.summary;
    return d;
  });
}
