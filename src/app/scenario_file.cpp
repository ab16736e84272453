#include "overtake/app/scenario_file.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include "overtake/app/config.hpp"

namespace overtake::app {
namespace {

using nlohmann::json;

// Reads fields of one JSON object, collecting errors that name the key's path.
class Fields {
 public:
  Fields(const json& j, std::string path, std::vector<std::string>& errors)
      : j_(j), path_(std::move(path)), errors_(errors) {
    if (!j_.is_object()) errors_.push_back(path_ + ": expected an object");
  }
  bool has(const char* key) {
    seen_.insert(key);
    return j_.is_object() && j_.contains(key);
  }
  double number(const char* key, double fallback, bool required = false) {
    if (!has(key)) {
      if (required) errors_.push_back(at(key) + ": missing");
      return fallback;
    }
    const json& v = j_.at(key);
    if (!v.is_number() || !std::isfinite(v.get<double>())) {
      errors_.push_back(at(key) + ": expected a finite number, got " + v.dump());
      return fallback;
    }
    return v.get<double>();
  }
  int integer(const char* key, int fallback, bool required = false) {
    if (!has(key)) {
      if (required) errors_.push_back(at(key) + ": missing");
      return fallback;
    }
    const json& v = j_.at(key);
    if (!v.is_number_integer()) {
      errors_.push_back(at(key) + ": expected an integer, got " + v.dump());
      return fallback;
    }
    return v.get<int>();
  }
  void check_unknown() const {
    if (!j_.is_object()) return;
    for (auto it = j_.begin(); it != j_.end(); ++it) {
      if (!seen_.count(it.key())) errors_.push_back(at(it.key().c_str()) + ": unknown key");
    }
  }
  std::string at(const char* key) const { return path_ + "." + key; }
  void error(const std::string& what) { errors_.push_back(path_ + ": " + what); }

 private:
  const json& j_;
  std::string path_;
  std::vector<std::string>& errors_;
  std::set<std::string> seen_;
};

}  // namespace

sim::Scenario parse_scenario(const json& j, std::string_view source, const core::RoadParams& road) {
  std::vector<std::string> errors;
  sim::Scenario sc;
  Fields top(j, "scenario", errors);
  if (top.has("name")) {
    if (j["name"].is_string()) sc.name = j["name"].get<std::string>();
    else errors.push_back("scenario.name: expected a string");
  }
  top.has("description");
  if (top.has("duration_s")) {
    const double d = top.number("duration_s", 0.0);
    if (!(d > 0.0)) errors.push_back("scenario.duration_s: must be more than 0");
    sc.duration_s = d;
  }
  auto lane_ok = [&](int lane) { return lane >= 0 && lane < road.lane_count; };
  if (top.has("ego")) {
    Fields ego(j["ego"], "scenario.ego", errors);
    sc.ego_s_m = ego.number("s_m", sc.ego_s_m);
    if (ego.has("lane")) {
      const int lane = ego.integer("lane", 1);
      if (!lane_ok(lane)) ego.error("lane " + std::to_string(lane) + " is not a lane of the road");
      sc.ego_d_m = core::lane_center_d(lane, road);
    }
    if (ego.has("d_m")) sc.ego_d_m = ego.number("d_m", sc.ego_d_m);
    sc.ego_speed_mps = ego.number("speed_mps", 0.0);
    if (sc.ego_speed_mps < 0.0) ego.error("speed_mps must be zero or more");
    ego.check_unknown();
  }
  if (top.has("cars")) {
    if (!j["cars"].is_array()) {
      errors.push_back("scenario.cars: expected a list");
    } else {
      for (std::size_t i = 0; i < j["cars"].size(); ++i) {
        Fields car(j["cars"][i], "scenario.cars[" + std::to_string(i) + "]", errors);
        sim::ScriptedCar c;
        const bool has_gap = car.has("gap_m");
        const bool has_s = car.has("s_m");
        if (has_gap == has_s) car.error("give exactly one of gap_m (from the ego) or s_m (absolute)");
        c.s_m = has_gap ? sc.ego_s_m + car.number("gap_m", 0.0) : car.number("s_m", 0.0);
        c.lane = car.integer("lane", 1, true);
        if (!lane_ok(c.lane)) car.error("lane " + std::to_string(c.lane) + " is not a lane of the road");
        c.speed_mps = car.number("speed_mps", 0.0, true);
        if (c.speed_mps < 0.0) car.error("speed_mps must be zero or more");
        car.check_unknown();
        sc.cars.push_back(c);
      }
    }
  }
  if (top.has("events")) {
    if (!j["events"].is_array()) {
      errors.push_back("scenario.events: expected a list");
    } else {
      for (std::size_t i = 0; i < j["events"].size(); ++i) {
        Fields ev(j["events"][i], "scenario.events[" + std::to_string(i) + "]", errors);
        sim::ScenarioEvent e;
        e.t_s = ev.number("t_s", 0.0, true);
        if (e.t_s < 0.0) ev.error("t_s must be zero or more");
        e.car = ev.integer("car", 0, true);
        if (e.car < 0 || e.car >= static_cast<int>(sc.cars.size())) {
          ev.error("car " + std::to_string(e.car) + " is not one of the scenario's " +
                   std::to_string(sc.cars.size()) + " cars");
        }
        const int kinds = static_cast<int>(ev.has("change_lane")) + static_cast<int>(ev.has("brake_mps2")) +
                          static_cast<int>(ev.has("speed_mps"));
        if (kinds != 1) {
          ev.error("give exactly one of change_lane, brake_mps2 (with duration_s) or speed_mps (with accel_mps2)");
        } else if (ev.has("change_lane")) {
          e.action = sim::ScenarioAction::change_lane;
          e.lane = ev.integer("change_lane", 0);
          if (!lane_ok(e.lane)) ev.error("change_lane " + std::to_string(e.lane) + " is not a lane of the road");
        } else if (ev.has("brake_mps2")) {
          e.action = sim::ScenarioAction::brake;
          e.rate_mps2 = ev.number("brake_mps2", 0.0);
          e.duration_s = ev.number("duration_s", 0.0, true);
          if (!(e.rate_mps2 > 0.0)) ev.error("brake_mps2 must be more than 0");
          if (!(e.duration_s > 0.0)) ev.error("duration_s must be more than 0");
        } else {
          e.action = sim::ScenarioAction::set_speed;
          e.speed_mps = ev.number("speed_mps", 0.0);
          e.rate_mps2 = ev.number("accel_mps2", 0.0, true);
          if (e.speed_mps < 0.0) ev.error("speed_mps must be zero or more");
          if (!(e.rate_mps2 > 0.0)) ev.error("accel_mps2 must be more than 0");
        }
        ev.check_unknown();
        sc.events.push_back(e);
      }
    }
  }
  top.check_unknown();
  if (!errors.empty()) {
    std::string msg = std::string(source) + ": invalid scenario";
    for (const auto& e : errors) msg += "\n  - " + e;
    throw ConfigError(msg);
  }
  std::stable_sort(sc.events.begin(), sc.events.end(),
                   [](const sim::ScenarioEvent& a, const sim::ScenarioEvent& b) { return a.t_s < b.t_s; });
  return sc;
}

sim::Scenario load_scenario(const std::filesystem::path& path, const core::RoadParams& road) {
  return parse_scenario(read_json_file(path), path.string(), road);
}

}  // namespace overtake::app
