#include "overtake/run/scenario_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <sstream>

#include "overtake/base/text.hpp"
#include "overtake/core/base64.hpp"
#include "overtake/run/config.hpp"
#include "overtake/sim/warm_up.hpp"

#include <zlib.h>

namespace overtake::run {

using base::json_text;
namespace {

using nlohmann::json;

std::string fmt(double v);

// What a scenario's numbers may be: a week at most (the longest run), speeds up to 100 m/s
// (224 mph), accelerations up to 50 m/s^2, positions within 100 km.
constexpr double kMaxDurationS = kMaxMinutes * 60.0;
constexpr double kMaxSpeedMps = 100.0;
constexpr double kMaxAccelMps2 = 50.0;
constexpr double kMaxDistanceM = 100000.0;

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
  /// A finite number within [lo, hi] (what makes physical sense for the key).
  double number(const char* key, double fallback, bool required, double lo, double hi) {
    if (!has(key)) {
      if (required) errors_.push_back(at(key) + ": missing");
      return fallback;
    }
    const json& v = j_.at(key);
    if (!v.is_number() || !std::isfinite(v.get<double>())) {
      errors_.push_back(at(key) + ": expected a finite number, got " + json_text(v));
      return fallback;
    }
    const double x = v.get<double>();
    if (!(x >= lo && x <= hi)) {
      errors_.push_back(at(key) + ": " + json_text(v) + " is out of range (" + fmt(lo) + " to " +
                        fmt(hi) + ")");
      return fallback;
    }
    return x;
  }
  /// An integer within [lo, hi]; never wrapped (2^32 + 1 is not 1).
  int integer(const char* key, int fallback, bool required, int lo, int hi) {
    if (!has(key)) {
      if (required) errors_.push_back(at(key) + ": missing");
      return fallback;
    }
    const json& v = j_.at(key);
    if (!v.is_number_integer()) {
      errors_.push_back(at(key) + ": expected an integer, got " + json_text(v));
      return fallback;
    }
    const bool in_range = v.is_number_unsigned()
                              ? v.get<std::uint64_t>() <= static_cast<std::uint64_t>(hi)
                              : v.get<std::int64_t>() >= lo && v.get<std::int64_t>() <= hi;
    if (!in_range) {
      errors_.push_back(at(key) + ": " + json_text(v) + " is out of range (" + std::to_string(lo) +
                        " to " + std::to_string(hi) + ")");
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

std::string fmt(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

void parse_expect(const json& j, sim::ScenarioExpect& ex, const core::RoadParams& road,
                  std::vector<std::string>& errors) {
  Fields e(j, "scenario.expect", errors);
  const auto count = [&](const char* key, std::optional<int>& out) {
    if (e.has(key)) out = e.integer(key, 0, false, 0, 1000000);
  };
  count("at_fault_collisions", ex.max_at_fault_collisions);
  count("collisions", ex.max_collisions);
  count("incidents", ex.max_incidents);
  if (e.has("reach_lane")) {
    Fields r(j["reach_lane"], "scenario.expect.reach_lane", errors);
    ex.reach_lane = r.integer("lane", 0, true, 0, road.lane_count - 1);
    ex.reach_lane_by_s = r.number("by_s", 0.0, true, 0.0, kMaxDurationS);
    r.check_unknown();
  }
  if (e.has("min_distance_m")) {
    ex.min_distance_m = e.number("min_distance_m", 0.0, false, 0.0, 1e9);
  }
  e.check_unknown();
}

std::string text_of(const json& j, const char* key, const std::string& path,
                    std::vector<std::string>& errors) {
  if (!j.contains(key)) return {};
  if (!j[key].is_string()) {
    errors.push_back(path + "." + key + ": expected a string");
    return {};
  }
  return j[key].get<std::string>();
}

void parse_cut(const json& j, sim::ScenarioCut& cut, std::vector<std::string>& errors) {
  Fields c(j, "scenario.cut", errors);
  if (c.has("traffic")) {
    const std::string t = text_of(j, "traffic", "scenario.cut", errors);
    if (t == "replayed") {
      cut.replayed = true;
    } else if (t != "reactive") {
      errors.push_back("scenario.cut.traffic: '" + t + "' is neither reactive nor replayed");
    }
  } else {
    errors.push_back("scenario.cut.traffic: missing");
  }
  cut.start_s = c.number("start_s", 0.0, true, 0.0, kMaxDurationS);
  cut.at_s = c.number("at_s", 0.0, true, 0.0, kMaxDurationS);
  cut.lead_in_s = c.number("lead_in_s", 0.0, false, 0.0, kMaxDurationS);
  if (c.has("map")) cut.map = text_of(j, "map", "scenario.cut", errors);
  if (c.has("from")) {  // where it was cut from (shown by the viewer)
    const json& f = j["from"];
    if (!f.is_object()) {
      errors.push_back("scenario.cut.from: expected an object");
    } else {
      cut.from_replay = text_of(f, "replay", "scenario.cut.from", errors);
      cut.incident = text_of(f, "incident", "scenario.cut.from", errors);
      if (f.contains("policy")) cut.from_policy = text_of(f, "policy", "scenario.cut.from", errors);
    }
  }
  const auto blob = [&](const char* key, std::string& out, bool required) {
    if (!c.has(key)) {
      if (required) errors.push_back(c.at(key) + ": missing");
      return;
    }
    try {
      out = unpack_blob(text_of(j, key, "scenario.cut", errors), c.at(key));
    } catch (const ConfigError& e) {
      errors.emplace_back(e.what());
    }
  };
  blob("checkpoint", cut.checkpoint, true);
  blob("recorded_traffic", cut.recorded, cut.replayed);
  if (c.has("warm_up")) {
    const json& w = j["warm_up"];
    if (!w.is_object()) {
      errors.push_back("scenario.cut.warm_up: expected an object");
    } else {
      Fields f(w, "scenario.cut.warm_up", errors);
      cut.warm_up_start_s = f.number("start_s", 0.0, true, 0.0, kMaxDurationS);
      cut.warm_up_cycles = std::lround(
          f.number("cycles", 0.0, true, 0.0, static_cast<double>(sim::kMaxWarmUpCycles)));
      (void)f.number("in_step_cycles", 0.0, false, 1.0, 100000.0);  // also in the bytes
      if (f.has("from_run_start") && !w["from_run_start"].is_boolean()) {
        errors.push_back("scenario.cut.warm_up.from_run_start: expected true or false");
      }
      if (!f.has("telemetry")) {
        errors.push_back("scenario.cut.warm_up.telemetry: missing");
      } else {
        try {
          cut.warm_up = unpack_blob(text_of(w, "telemetry", "scenario.cut.warm_up", errors),
                                    "scenario.cut.warm_up.telemetry", kMaxWarmUpBytes);
        } catch (const ConfigError& e) {
          errors.emplace_back(e.what());
        }
      }
      f.check_unknown();
    }
  }
  c.check_unknown();
}

}  // namespace

std::string pack_blob(std::string_view bytes) {
  uLongf size = compressBound(static_cast<uLong>(bytes.size()));
  std::string out(size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(out.data()), &size,
                reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uLong>(bytes.size()),
                Z_BEST_COMPRESSION) != Z_OK) {
    throw std::runtime_error("cannot compress " + std::to_string(bytes.size()) + " bytes");
  }
  out.resize(size);
  return core::base64_encode(out);
}

std::string unpack_blob(std::string_view text, std::string_view what, std::size_t max_bytes) {
  const std::size_t kMaxBytes = max_bytes;
  const std::optional<std::string> packed = core::base64_decode(text);
  if (!packed) throw ConfigError(std::string(what) + ": not base64");
  z_stream z{};
  if (inflateInit(&z) != Z_OK) throw ConfigError(std::string(what) + ": cannot inflate");
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(packed->data()));
  z.avail_in = static_cast<uInt>(packed->size());
  std::string out;
  char chunk[1 << 16];
  int rc = Z_OK;
  while (rc == Z_OK) {
    z.next_out = reinterpret_cast<Bytef*>(chunk);
    z.avail_out = sizeof chunk;
    rc = inflate(&z, Z_NO_FLUSH);
    out.append(chunk, sizeof chunk - z.avail_out);
    if (out.size() > kMaxBytes) rc = Z_MEM_ERROR;
    if (rc == Z_BUF_ERROR && z.avail_in == 0) break;
  }
  const std::size_t trailing = z.avail_in;
  inflateEnd(&z);
  if (rc != Z_STREAM_END) {
    throw ConfigError(std::string(what) + (out.size() > kMaxBytes
                                               ? ": more than " + std::to_string(kMaxBytes >> 20U) +
                                                     " MB once inflated (the most a scenario's "
                                                     "blob may hold)"
                                               : std::string(": damaged or truncated (zlib)")));
  }
  if (trailing > 0) {
    throw ConfigError(std::string(what) + ": " + std::to_string(trailing) +
                      " bytes after the end of the zlib stream (damaged, or two blobs in one)");
  }
  return out;
}

namespace {

// The ego's start (`ego`).
void parse_ego(const json& j, sim::Scenario& sc, const core::RoadParams& road,
               std::vector<std::string>& errors) {
  const double road_width = core::road_width_m(road);
  Fields ego(j, "scenario.ego", errors);
  sc.ego_s_m = ego.number("s_m", sc.ego_s_m, false, -kMaxDistanceM, kMaxDistanceM);
  if (ego.has("lane")) {
    const int lane = ego.integer("lane", 1, false, 0, road.lane_count - 1);
    sc.ego_d_m = core::lane_center_d(lane, road);
  }
  if (ego.has("d_m")) sc.ego_d_m = ego.number("d_m", sc.ego_d_m, false, 0.0, road_width);
  sc.ego_speed_mps = ego.number("speed_mps", 0.0, false, 0.0, kMaxSpeedMps);
  ego.check_unknown();
}

// The scripted cars (`cars`), placed from the ego's start.
void parse_cars(const json& j, sim::Scenario& sc, const core::RoadParams& road,
                std::vector<std::string>& errors) {
  if (!j.is_array()) {
    errors.push_back("scenario.cars: expected a list");
  } else if (j.size() > kMaxScenarioCars) {
    errors.push_back("scenario.cars: " + std::to_string(j.size()) + " cars, more than the " +
                     std::to_string(kMaxScenarioCars) + " a scenario may place");
  } else {
    for (std::size_t i = 0; i < j.size(); ++i) {
      Fields car(j[i], "scenario.cars[" + std::to_string(i) + "]", errors);
      sim::ScriptedCar c;
      const bool has_gap = car.has("gap_m");
      const bool has_s = car.has("s_m");
      if (has_gap == has_s) car.error("give exactly one of gap_m (from the ego) or s_m (absolute)");
      c.s_m = has_gap ? sc.ego_s_m + car.number("gap_m", 0.0, false, -kMaxDistanceM, kMaxDistanceM)
                      : car.number("s_m", 0.0, false, -kMaxDistanceM, kMaxDistanceM);
      c.lane = car.integer("lane", 1, true, 0, road.lane_count - 1);
      c.speed_mps = car.number("speed_mps", 0.0, true, 0.0, kMaxSpeedMps);
      car.check_unknown();
      sc.cars.push_back(c);
    }
  }
}

// The timed events of the scripted cars (`events`).
void parse_events(const json& j, sim::Scenario& sc, const core::RoadParams& road,
                  std::vector<std::string>& errors) {
  if (!j.is_array()) {
    errors.push_back("scenario.events: expected a list");
  } else if (j.size() > kMaxScenarioEvents) {
    errors.push_back("scenario.events: " + std::to_string(j.size()) + " events, more than the " +
                     std::to_string(kMaxScenarioEvents) + " a scenario may hold");
  } else {
    for (std::size_t i = 0; i < j.size(); ++i) {
      Fields ev(j[i], "scenario.events[" + std::to_string(i) + "]", errors);
      sim::ScenarioEvent e;
      e.t_s = ev.number("t_s", 0.0, true, 0.0, kMaxDurationS);
      e.car = ev.integer("car", 0, true, 0, static_cast<int>(kMaxScenarioCars) - 1);
      if (e.car < 0 || e.car >= static_cast<int>(sc.cars.size())) {
        ev.error("car " + std::to_string(e.car) + " is not one of the scenario's " +
                 std::to_string(sc.cars.size()) + " cars");
      }
      const int kinds = static_cast<int>(ev.has("change_lane")) +
                        static_cast<int>(ev.has("brake_mps2")) +
                        static_cast<int>(ev.has("speed_mps"));
      if (kinds != 1) {
        ev.error(
            "give exactly one of change_lane, brake_mps2 (with duration_s) or speed_mps (with "
            "accel_mps2)");
      } else if (ev.has("change_lane")) {
        e.action = sim::ScenarioAction::change_lane;
        e.lane = ev.integer("change_lane", 0, false, 0, road.lane_count - 1);
      } else if (ev.has("brake_mps2")) {
        e.action = sim::ScenarioAction::brake;
        e.rate_mps2 = ev.number("brake_mps2", 0.0, false, 0.0, kMaxAccelMps2);
        e.duration_s = ev.number("duration_s", 0.0, true, 0.0, kMaxDurationS);
        if (!(e.rate_mps2 > 0.0)) ev.error("brake_mps2 must be more than 0");
        if (!(e.duration_s > 0.0)) ev.error("duration_s must be more than 0");
      } else {
        e.action = sim::ScenarioAction::set_speed;
        e.speed_mps = ev.number("speed_mps", 0.0, false, 0.0, kMaxSpeedMps);
        e.rate_mps2 = ev.number("accel_mps2", 0.0, true, 0.0, kMaxAccelMps2);
        if (!(e.rate_mps2 > 0.0)) ev.error("accel_mps2 must be more than 0");
      }
      ev.check_unknown();
      sc.events.push_back(e);
    }
  }
}

}  // namespace

sim::Scenario parse_scenario(const json& j, std::string_view source, const core::RoadParams& road) {
  std::vector<std::string> errors;
  sim::Scenario sc;
  Fields top(j, "scenario", errors);
  if (top.has("name")) {
    if (j["name"].is_string())
      sc.name = j["name"].get<std::string>();
    else
      errors.push_back("scenario.name: expected a string");
  }
  if (top.has("description")) sc.description = text_of(j, "description", "scenario", errors);
  if (top.has("expect")) parse_expect(j["expect"], sc.expect, road, errors);
  if (top.has("cut")) {
    sc.cut.emplace();
    parse_cut(j["cut"], *sc.cut, errors);
    for (const char* key : {"ego", "cars", "events"}) {
      if (j.contains(key)) {
        errors.push_back(std::string("scenario.") + key +
                         ": a cut scenario starts from its checkpoint (no " + key + ")");
      }
    }
  }
  if (top.has("duration_s")) {
    const double d = top.number("duration_s", 1.0, false, 0.0, kMaxDurationS);
    if (!(d > 0.0)) errors.push_back("scenario.duration_s: must be more than 0");
    sc.duration_s = d;
  }
  // The lead-in is not judged: one as long as the scenario leaves nothing to judge, and the
  // scenario would pass whatever the planner did.
  if (sc.cut && sc.duration_s && *sc.duration_s > 0.0 && sc.cut->lead_in_s >= *sc.duration_s) {
    errors.push_back("scenario.cut.lead_in_s: " + fmt(sc.cut->lead_in_s) +
                     " s is not less than scenario.duration_s (" + fmt(*sc.duration_s) +
                     " s): nothing after the lead-in would be judged");
  }
  if (top.has("ego")) parse_ego(j["ego"], sc, road, errors);
  if (top.has("cars")) parse_cars(j["cars"], sc, road, errors);
  if (top.has("events")) parse_events(j["events"], sc, road, errors);
  top.check_unknown();
  if (!errors.empty()) {
    std::string msg = std::string(source) + ": invalid scenario";
    for (const auto& e : errors) msg += "\n  - " + e;
    throw ConfigError(msg);
  }
  std::stable_sort(
      sc.events.begin(), sc.events.end(),
      [](const sim::ScenarioEvent& a, const sim::ScenarioEvent& b) { return a.t_s < b.t_s; });
  return sc;
}

sim::Scenario parse_scenario_text(std::string_view text, std::string_view source,
                                  const core::RoadParams& road) {
  return parse_scenario(parse_json_text(text, source), source, road);
}

sim::Scenario load_scenario(const std::filesystem::path& path, const core::RoadParams& road) {
  return parse_scenario(read_json_file(path), path.string(), road);
}

}  // namespace overtake::run
