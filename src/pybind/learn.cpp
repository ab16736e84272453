// The learning environment from Python (`overtake._overtake.VecEnvCore`, wrapped by
// python/overtake/learning.py): numpy arrays in and out, the worlds stepped with the GIL
// released, on the environment's own threads.
#include "learn.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

#include "convert.hpp"
#include "overtake/learn/driver.hpp"
#include "overtake/learn/observation.hpp"
#include "overtake/learn/params.hpp"
#include "overtake/learn/vec_env.hpp"
#include "overtake/python/bridge.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"

namespace overtake::pybind {
namespace {

namespace py = pybind11;
using learn::ActionKind;

// The array `given` as C-contiguous values of T, of the shape wanted (a dimension of -1 takes
// any length), or TypeError / ValueError naming what is wrong.
template <typename T>
py::array_t<T, py::array::c_style | py::array::forcecast> checked_array(
    const py::handle& given, const std::vector<py::ssize_t>& shape, const char* what) {
  py::array a = py::array::ensure(given);
  if (!a) throw py::type_error(std::string(what) + ": not an array of numbers");
  if (a.ndim() != static_cast<py::ssize_t>(shape.size())) {
    throw py::value_error(std::string(what) + ": an array of " + std::to_string(shape.size()) +
                          " dimensions is wanted, not " + std::to_string(a.ndim()));
  }
  for (std::size_t k = 0; k < shape.size(); ++k) {
    if (shape[k] >= 0 && a.shape(static_cast<py::ssize_t>(k)) != shape[k]) {
      throw py::value_error(std::string(what) + ": dimension " + std::to_string(k) + " is " +
                            std::to_string(a.shape(static_cast<py::ssize_t>(k))) + ", not " +
                            std::to_string(shape[k]));
    }
  }
  const char kind = a.dtype().kind();
  if (kind != 'i' && kind != 'u' && kind != 'f' && kind != 'b') {
    throw py::type_error(std::string(what) + ": an array of numbers is wanted, not of dtype " +
                         py::str(a.dtype()).cast<std::string>());
  }
  auto converted = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!converted) throw py::type_error(std::string(what) + ": cannot be read as numbers");
  return converted;
}

class VecEnvCore {
 public:
  VecEnvCore(std::size_t num_envs, std::uint64_t seed, const std::string& actions,
             const std::optional<std::string>& map, const std::string& traffic,
             const std::optional<std::string>& config, const std::optional<std::string>& params,
             double minutes, int threads, const std::string& name) {
    learn::VecEnvSpec spec;
    try {
      spec.num_envs = num_envs;
      spec.seed = seed;
      spec.actions = learn::parse_action_kind(actions);
      if (map) spec.map = *map;
      if (config) spec.config = *config;
      if (params) spec.params = *params;
      spec.traffic = traffic;
      spec.minutes = minutes;
      spec.threads = threads;
      spec.name = name;
      env_ = std::make_unique<learn::VecEnv>(spec);
    } catch (const std::invalid_argument& e) {
      throw py::value_error(e.what());
    } catch (const run::ConfigError& e) {
      throw py::value_error(e.what());
    }
  }

  py::array_t<float> reset(const std::optional<std::uint64_t>& seed) {
    py::array_t<float> obs(shape_of_observations());
    float* out = obs.mutable_data();
    {
      py::gil_scoped_release nogil;
      env_->reset(seed, out);
    }
    return obs;
  }

  py::tuple step(const py::handle& actions) {
    const auto n = static_cast<py::ssize_t>(env_->num_envs());
    learn::Actions a;
    py::object keep;  // the converted actions, alive while the worlds read them
    switch (env_->action_kind()) {
      case ActionKind::meta: {
        (void)checked_array<double>(actions, {n}, "actions");  // the shape, before the values
        check_whole(actions);
        auto arr = checked_array<std::int64_t>(actions, {n}, "actions");
        a.meta = arr.data();
        keep = arr;
        break;
      }
      case ActionKind::continuous: {
        auto arr = checked_array<float>(actions, {n, 2}, "actions");
        a.continuous = arr.data();
        keep = arr;
        break;
      }
      case ActionKind::path: {
        auto arr = checked_array<double>(actions, {n, -1, 2}, "actions");
        a.path = arr.data();
        a.path_points = static_cast<std::size_t>(arr.shape(1));
        keep = arr;
        break;
      }
    }
    py::array_t<float> obs(shape_of_observations());
    py::array_t<float> reward(n);
    py::array_t<bool> terminated(n);
    py::array_t<bool> truncated(n);
    learn::StepOutputs out;
    out.observation = obs.mutable_data();
    out.reward = reward.mutable_data();
    static_assert(sizeof(bool) == sizeof(std::uint8_t));
    out.terminated = reinterpret_cast<std::uint8_t*>(terminated.mutable_data());
    out.truncated = reinterpret_cast<std::uint8_t*>(truncated.mutable_data());
    try {
      py::gil_scoped_release nogil;
      env_->step(a, out);
    } catch (const std::invalid_argument& e) {
      throw py::value_error(e.what());
    }
    return py::make_tuple(obs, reward, terminated, truncated);
  }

  // The envs' figures after the last call, as arrays (Gymnasium's info of a vector env).
  py::dict status() const {
    const std::size_t n = env_->num_envs();
    py::array_t<std::uint64_t> seed(static_cast<py::ssize_t>(n));
    py::array_t<std::int64_t> episode(static_cast<py::ssize_t>(n)),
        length(static_cast<py::ssize_t>(n)), lane(static_cast<py::ssize_t>(n)),
        target_lane(static_cast<py::ssize_t>(n)), collisions(static_cast<py::ssize_t>(n)),
        at_fault(static_cast<py::ssize_t>(n)), incidents(static_cast<py::ssize_t>(n));
    py::array_t<double> time(static_cast<py::ssize_t>(n)), distance(static_cast<py::ssize_t>(n)),
        speed(static_cast<py::ssize_t>(n)), target_speed(static_cast<py::ssize_t>(n)),
        ret(static_cast<py::ssize_t>(n));
    py::array_t<bool> was_reset(static_cast<py::ssize_t>(n));
    for (std::size_t i = 0; i < n; ++i) {
      const learn::EnvStatus& s = env_->status(i);
      const auto k = static_cast<py::ssize_t>(i);
      seed.mutable_at(k) = s.episode_seed;
      episode.mutable_at(k) = s.episode;
      length.mutable_at(k) = s.episode_length;
      lane.mutable_at(k) = s.lane;
      target_lane.mutable_at(k) = s.target_lane;
      collisions.mutable_at(k) = static_cast<std::int64_t>(s.collisions);
      at_fault.mutable_at(k) = static_cast<std::int64_t>(s.at_fault);
      incidents.mutable_at(k) = static_cast<std::int64_t>(s.incidents);
      time.mutable_at(k) = s.time_s;
      distance.mutable_at(k) = s.distance_m;
      speed.mutable_at(k) = s.speed_mps;
      target_speed.mutable_at(k) = s.target_speed_mps;
      ret.mutable_at(k) = s.episode_return;
      was_reset.mutable_at(k) = s.was_reset;
    }
    py::dict d;
    d["episode_seed"] = seed;
    d["episode"] = episode;
    d["episode_length"] = length;
    d["episode_return"] = ret;
    d["was_reset"] = was_reset;
    d["time_s"] = time;
    d["distance_m"] = distance;
    d["speed_mps"] = speed;
    d["lane"] = lane;
    d["target_lane"] = target_lane;
    d["target_speed_mps"] = target_speed;
    d["collisions"] = collisions;
    d["at_fault"] = at_fault;
    d["incidents"] = incidents;
    return d;
  }

  py::object last_report(std::size_t env) const {
    return to_python(env_->last_report(checked(env)));
  }
  py::object report(std::size_t env) const { return to_python(env_->report(checked(env))); }
  py::dict telemetry(std::size_t env) const {
    try {
      return python::telemetry_to_dict(env_->telemetry(checked(env)));
    } catch (const std::logic_error& e) {
      throw py::value_error(e.what());
    }
  }

  [[nodiscard]] std::size_t num_envs() const { return env_->num_envs(); }
  [[nodiscard]] std::size_t observation_size() const { return env_->observation_size(); }
  [[nodiscard]] int lanes() const { return env_->lanes(); }
  [[nodiscard]] double cruise_speed_mps() const { return env_->cruise_speed_mps(); }
  [[nodiscard]] std::string actions() const {
    return std::string(learn::to_string(env_->action_kind()));
  }
  [[nodiscard]] int max_path_points() const { return env_->params().max_path_points; }
  [[nodiscard]] py::object params() const {
    return to_python(learn::env_params_json(env_->params()));
  }

 private:
  [[nodiscard]] std::vector<py::ssize_t> shape_of_observations() const {
    return {static_cast<py::ssize_t>(env_->num_envs()),
            static_cast<py::ssize_t>(env_->observation_size())};
  }

  [[nodiscard]] std::size_t checked(std::size_t env) const {
    if (env >= env_->num_envs()) {
      throw py::index_error("env " + std::to_string(env) + " of " +
                            std::to_string(env_->num_envs()));
    }
    return env;
  }

  // A meta-action given as a float must be whole (1.5 is no action), checked before the
  // floats are cast to integers.
  static void check_whole(const py::handle& given) {
    py::array original = py::array::ensure(given);
    if (!original || original.dtype().kind() != 'f') return;
    auto f = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(original);
    for (py::ssize_t i = 0; i < f.size(); ++i) {
      const double x = f.data()[i];
      if (!std::isfinite(x) || x != std::floor(x) || std::abs(x) > 1e9) {
        throw py::value_error("the action of env " + std::to_string(i) + " is " +
                              py::str(py::float_(x)).cast<std::string>() +
                              ": a meta-action is a whole number, 0 to 4");
      }
    }
  }

  std::unique_ptr<learn::VecEnv> env_;
};

// A learned policy's decisions carried out as the environment carries them out, from a
// planner's seat (learn::PolicyDriver): the telemetry dict in, the observation or the path out.
class PolicyDriverCore {
 public:
  PolicyDriverCore(const std::string& actions, const std::optional<std::string>& map,
                   const std::optional<std::string>& config,
                   const std::optional<std::string>& params) {
    try {
      config_ =
          run::load_config(config ? std::optional<std::filesystem::path>(*config) : std::nullopt);
      track_ = run::load_track(map ? std::optional<std::filesystem::path>(*map) : std::nullopt);
      driver_ = std::make_unique<learn::PolicyDriver>(
          track_->line, track_->map.loop_length_m, config_,
          learn::load_env_params(params ? std::optional<std::filesystem::path>(*params)
                                        : std::nullopt),
          learn::parse_action_kind(actions));
    } catch (const std::invalid_argument& e) {
      throw py::value_error(e.what());
    } catch (const run::ConfigError& e) {
      throw py::value_error(e.what());
    }
  }

  // One call of the planner: the telemetry read once; when a decision is due, `policy` is
  // asked with the observation; then the path.
  py::tuple call(const py::handle& telemetry, const py::object& policy) {
    const core::Telemetry t = python::telemetry_from_dict(telemetry);
    py::object action = py::none();
    if (driver_->decision_due(t)) {
      py::array_t<float> obs(static_cast<py::ssize_t>(driver_->observation_size()));
      driver_->observe(t, std::span<float>(obs.mutable_data(), driver_->observation_size()));
      action = policy(obs);
    }
    core::PlanResult plan;
    try {
      if (action.is_none()) {
        plan = driver_->plan(t, nullptr, nullptr);
      } else if (py::isinstance<py::int_>(action) || py::array::ensure(action).ndim() == 0) {
        const double x = py::float_(action).cast<double>();
        if (!std::isfinite(x) || x != std::floor(x))
          throw std::invalid_argument("the policy's action is not a whole number");
        const auto a = static_cast<std::int64_t>(x);
        plan = driver_->plan(t, &a, nullptr);
      } else {
        auto arr = checked_array<float>(action, {2}, "the policy's action");
        plan = driver_->plan(t, nullptr, arr.data());
      }
    } catch (const std::invalid_argument& e) {
      throw py::value_error(e.what());
    }
    return path_to_python(plan.path);
  }

  [[nodiscard]] py::dict targets() const {
    py::dict d;
    d["lane"] = driver_->targets().target_lane;
    d["speed_mps"] = driver_->targets().target_speed_mps;
    return d;
  }

 private:
  run::Config config_;
  std::shared_ptr<const run::Track> track_;
  std::unique_ptr<learn::PolicyDriver> driver_;  // refers to config_ and track_
};

}  // namespace

void register_learning(py::module_& m) {
  py::class_<PolicyDriverCore>(m, "PolicyDriverCore")
      .def(py::init<const std::string&, const std::optional<std::string>&,
                    const std::optional<std::string>&, const std::optional<std::string>&>(),
           py::arg("actions"), py::arg("map"), py::arg("config"), py::arg("params"))
      .def("__call__", &PolicyDriverCore::call, py::arg("telemetry"), py::arg("policy"))
      .def_property_readonly("targets", &PolicyDriverCore::targets);
  py::class_<VecEnvCore>(m, "VecEnvCore")
      .def(py::init<std::size_t, std::uint64_t, const std::string&,
                    const std::optional<std::string>&, const std::string&,
                    const std::optional<std::string>&, const std::optional<std::string>&, double,
                    int, const std::string&>(),
           py::arg("num_envs"), py::arg("seed"), py::arg("actions"), py::arg("map"),
           py::arg("traffic"), py::arg("config"), py::arg("params"), py::arg("minutes"),
           py::arg("threads"), py::arg("name"))
      .def("reset", &VecEnvCore::reset, py::arg("seed") = py::none())
      .def("step", &VecEnvCore::step, py::arg("actions"))
      .def("status", &VecEnvCore::status)
      .def("last_report", &VecEnvCore::last_report, py::arg("env"))
      .def("report", &VecEnvCore::report, py::arg("env"))
      .def("telemetry", &VecEnvCore::telemetry, py::arg("env"))
      .def_property_readonly("num_envs", &VecEnvCore::num_envs)
      .def_property_readonly("observation_size", &VecEnvCore::observation_size)
      .def_property_readonly("lanes", &VecEnvCore::lanes)
      .def_property_readonly("cruise_speed_mps", &VecEnvCore::cruise_speed_mps)
      .def_property_readonly("actions", &VecEnvCore::actions)
      .def_property_readonly("max_path_points", &VecEnvCore::max_path_points)
      .def_property_readonly("params", &VecEnvCore::params);
  m.attr("META_ACTIONS") = learn::kMetaActions;
  m.attr("EGO_FEATURES") = learn::kEgoFeatures;
  m.attr("SLOT_FEATURES") = learn::kSlotFeatures;
}

}  // namespace overtake::pybind
