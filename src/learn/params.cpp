#include "overtake/learn/params.hpp"

#include <cmath>
#include <functional>
#include <map>
#include <string>

#include "overtake/run/config.hpp"
#include "overtake/run/resources.hpp"

namespace overtake::learn {

using nlohmann::json;
using run::ConfigError;

namespace {

// Every number of the params by its key in config/learn.json.
std::map<std::string, double*> number_keys(EnvParams& p) {
  ObservationParams& o = p.observation;
  RewardParams& r = p.reward;
  return {{"speed_step_mps", &p.speed_step_mps},
          {"observation.range_m", &o.range_m},
          {"observation.speed_scale_mps", &o.speed_scale_mps},
          {"observation.accel_scale_mps2", &o.accel_scale_mps2},
          {"observation.time_scale_s", &o.time_scale_s},
          {"reward.progress", &r.progress},
          {"reward.collision", &r.collision},
          {"reward.at_fault", &r.at_fault},
          {"reward.speeding", &r.speeding},
          {"reward.max_acceleration", &r.max_acceleration},
          {"reward.max_jerk", &r.max_jerk},
          {"reward.outside_lane", &r.outside_lane},
          {"reward.lane_change", &r.lane_change}};
}

std::map<std::string, int*> whole_keys(EnvParams& p) {
  return {{"decision_steps", &p.decision_steps}, {"max_path_points", &p.max_path_points}};
}

// One key (a.b for a nested one) read into `p`.
void apply_key(EnvParams& p, const std::string& key, const json& v,
               const std::function<void(const std::string&, const std::string&)>& fail) {
  const auto numbers = number_keys(p);
  const auto wholes = whole_keys(p);
  if (const auto n = numbers.find(key); n != numbers.end()) {
    if (!v.is_number()) fail(key, "must be a number");
    *n->second = v.get<double>();
  } else if (const auto w = wholes.find(key); w != wholes.end()) {
    if (!v.is_number() || v.get<double>() != std::floor(v.get<double>()) ||
        std::abs(v.get<double>()) > 1e6)
      fail(key, "must be a whole number");
    *w->second = static_cast<int>(v.get<double>());
  } else if (key == "terminate_on_collision") {
    if (!v.is_boolean()) fail(key, "must be true or false");
    p.terminate_on_collision = v.get<bool>();
  } else {
    fail(key, "is not a key of the learning environment's params");
  }
}

}  // namespace

void EnvParams::validate() const {
  const auto bad = [](const std::string& key, const std::string& why) {
    throw ConfigError("learn params: " + key + " " + why);
  };
  if (decision_steps < 1 || decision_steps > 1000) bad("decision_steps", "must be from 1 to 1000");
  if (!(speed_step_mps > 0.0) || speed_step_mps > 30.0)
    bad("speed_step_mps", "must be more than 0 and at most 30");
  const ObservationParams& o = observation;
  for (const auto& [key, x] : {std::pair{"observation.range_m", o.range_m},
                               {"observation.speed_scale_mps", o.speed_scale_mps},
                               {"observation.accel_scale_mps2", o.accel_scale_mps2},
                               {"observation.time_scale_s", o.time_scale_s}}) {
    if (!(x > 0.0) || !std::isfinite(x)) bad(key, "must be more than 0");
  }
  const RewardParams& r = reward;
  for (const double x : {r.progress, r.collision, r.at_fault, r.speeding, r.max_acceleration,
                         r.max_jerk, r.outside_lane, r.lane_change}) {
    if (!std::isfinite(x) || std::abs(x) > 1e9) bad("reward", "weights must be finite numbers");
  }
  if (max_path_points < 1 || max_path_points > 100000)
    bad("max_path_points", "must be from 1 to 100000");
}

void apply_env_params(EnvParams& p, const json& j, const std::string& source) {
  const auto fail = [&](const std::string& key, const std::string& why) {
    throw ConfigError(source + ": " + key + ": " + why);
  };
  if (!j.is_object()) fail("(top)", "must be an object");
  for (const auto& [key, v] : j.items()) {
    if (key == "//" || key.starts_with("_")) continue;  // comments
    if (key == "observation" || key == "reward") {
      if (!v.is_object()) fail(key, "must be an object");
      for (const auto& [k, x] : v.items()) apply_key(p, key + "." + k, x, fail);
    } else {
      apply_key(p, key, v, fail);
    }
  }
  try {
    p.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(source + ": " +
                      std::string(e.what()).substr(std::string("learn params: ").size()));
  }
}

EnvParams load_env_params(const std::optional<std::filesystem::path>& path) {
  EnvParams p;
  const auto text = resources::embedded_file("config/learn.json");
  if (!text) throw ConfigError("built-in config/learn.json is missing from this build");
  apply_env_params(p, run::parse_json_text(*text, "built-in config/learn.json"),
                   "built-in config/learn.json");
  if (path) apply_env_params(p, run::read_json_file(*path), path->string());
  return p;
}

json env_params_json(const EnvParams& p) {
  EnvParams copy = p;
  json j = {{"terminate_on_collision", p.terminate_on_collision}};
  for (const auto& [key, value] : whole_keys(copy)) j[key] = *value;
  for (const auto& [key, value] : number_keys(copy)) {
    const auto dot = key.find('.');
    if (dot == std::string::npos) {
      j[key] = *value;
    } else {
      j[key.substr(0, dot)][key.substr(dot + 1)] = *value;
    }
  }
  return j;
}

}  // namespace overtake::learn
