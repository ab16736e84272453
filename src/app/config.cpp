#include "overtake/app/config.hpp"

#include <set>
#include <sstream>

#include "overtake/app/io.hpp"
#include "overtake/app/resources.hpp"
#include "overtake/core/hash.hpp"
#include "overtake/core/text_check.hpp"

namespace overtake::app {
namespace {

using nlohmann::json;

std::string type_name(const json& v) {
  if (v.is_boolean()) return "a boolean";
  if (v.is_number_integer() || v.is_number_unsigned()) return "an integer";
  if (v.is_number()) return "a number";
  if (v.is_string()) return "a string";
  if (v.is_array()) return "a list";
  if (v.is_object()) return "an object";
  return "null";
}

// Reads the keys present in one JSON object into a params struct through its field list.
class Reader {
 public:
  Reader(const json& j, std::string path, std::vector<std::string>& errors)
      : j_(j), path_(std::move(path)), errors_(errors) {}

  void operator()(const char* key, double& field) {
    const json* v = find(key);
    if (!v) return;
    if (!v->is_number()) return wrong(key, "a number", *v);
    field = v->get<double>();
  }
  void operator()(const char* key, int& field) {
    const json* v = find(key);
    if (!v) return;
    if (!v->is_number_integer() && !v->is_number_unsigned()) return wrong(key, "an integer", *v);
    const auto x = v->get<long long>();
    if (x < -1000000000LL || x > 1000000000LL) return wrong(key, "an integer of sensible size", *v);
    field = static_cast<int>(x);
  }
  void operator()(const char* key, bool& field) {
    const json* v = find(key);
    if (!v) return;
    if (!v->is_boolean()) return wrong(key, "true or false", *v);
    field = v->get<bool>();
  }
  void operator()(const char* key, std::vector<double>& field) {
    const json* v = find(key);
    if (!v) return;
    if (!v->is_array()) return wrong(key, "a list of numbers", *v);
    std::vector<double> out;
    for (const json& e : *v) {
      if (!e.is_number()) return wrong(key, "a list of numbers", *v);
      out.push_back(e.get<double>());
    }
    field = std::move(out);
  }
  template <class S>
  void section(const char* key, S& sub) {
    const json* v = find(key);
    if (!v) return;
    if (!v->is_object()) return wrong(key, "an object", *v);
    Reader inner(*v, key_path(key), errors_);
    describe(inner, sub);
    inner.check_unknown();
  }
  void check_unknown() const {
    for (auto it = j_.begin(); it != j_.end(); ++it) {
      if (!seen_.count(it.key()))
        errors_.push_back("unknown key '" + key_path(it.key().c_str()) + "'");
    }
  }

 private:
  const json* find(const char* key) {
    seen_.insert(key);
    const auto it = j_.find(key);
    return it == j_.end() ? nullptr : &*it;
  }
  std::string key_path(const char* key) const { return path_.empty() ? key : path_ + "." + key; }
  void wrong(const char* key, const char* expected, const json& got) {
    errors_.push_back(key_path(key) + ": expected " + expected + ", got " + type_name(got) + " (" +
                      json_text(got) + ")");
  }
  const json& j_;
  std::string path_;
  std::vector<std::string>& errors_;
  std::set<std::string> seen_;
};

// Writes every field of a params struct into a JSON object.
class Writer {
 public:
  explicit Writer(json& j) : j_(j) {}
  template <class T>
  void operator()(const char* key, const T& field) {
    j_[key] = field;
  }
  template <class S>
  void section(const char* key, S& sub) {
    json inner = json::object();
    Writer w(inner);
    describe(w, sub);
    j_[key] = std::move(inner);
  }

 private:
  json& j_;
};

using planner::describe;
using sim::describe;

[[noreturn]] void fail(std::string_view source, const std::vector<std::string>& errors) {
  std::ostringstream os;
  os << source << ": invalid configuration";
  for (const auto& e : errors) os << "\n  - " << e;
  throw ConfigError(os.str());
}

}  // namespace

Config apply_config_json(Config base, const json& j, std::string_view source) {
  if (!j.is_object()) fail(source, {"the top level must be a JSON object"});
  std::vector<std::string> errors;
  Reader top(j, "", errors);
  top.section("road", base.road);
  top.section("car", base.car);
  top.section("world", base.world);
  top.section("planner", base.planner);
  top.check_unknown();
  if (!errors.empty()) fail(source, errors);
  // Facts the modules share live once in the file and are copied into each module's params.
  base.world.road = base.road;
  base.planner.road = base.road;
  base.world.car = base.car;
  base.planner.car = base.car;
  base.planner.step_s = base.world.step_s;
  auto problems = sim::validate(base.world);
  const auto planner_problems = planner::validate(base.planner);
  problems.insert(problems.end(), planner_problems.begin(), planner_problems.end());
  if (!problems.empty()) fail(source, problems);
  return base;
}

Config apply_config_text(Config base, std::string_view text, std::string_view source) {
  return apply_config_json(std::move(base), parse_json_text(text, source), source);
}

Config default_config() {
  const auto text = resources::embedded_file("config/overtake.json");
  if (!text) throw ConfigError("built-in config/overtake.json is missing from this build");
  return apply_config_json(Config{}, json::parse(*text), "built-in config/overtake.json");
}

json parse_json_text(std::string_view text, std::string_view source) {
  // A key given twice in one object is refused (the JSON library would keep the last one,
  // silently): the callback sees every key with the objects around it.
  struct Level {
    bool object = false;
    std::set<std::string> keys;
    std::string key;  // the last key read at this level
  };
  std::vector<Level> levels;
  std::string duplicate;
  const auto watch = [&](int, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        levels.push_back({event == json::parse_event_t::object_start, {}, {}});
        break;
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        if (!levels.empty()) levels.pop_back();
        break;
      case json::parse_event_t::key:
        if (!levels.empty() && parsed.is_string()) {
          Level& here = levels.back();
          here.key = parsed.get<std::string>();
          if (!here.keys.insert(here.key).second && duplicate.empty()) {
            for (const Level& l : levels)
              duplicate += l.object ? (duplicate.empty() ? "" : ".") + l.key : "[]";
          }
        }
        break;
      default:
        break;
    }
    return true;
  };
  json j;
  try {
    core::require_json_depth(text, source);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(e.what());
  }
  try {
    j = json::parse(text, watch);
  } catch (const json::exception& e) {  // parse_error; out_of_range for a number like 1e999
    throw ConfigError(std::string(source) + ": not valid JSON: " + e.what());
  }
  if (!duplicate.empty()) {
    throw ConfigError(std::string(source) + ": the key '" + duplicate + "' is given twice");
  }
  return j;
}

json read_json_file(const std::filesystem::path& path) {
  std::string text;
  try {
    text = read_file(path, kMaxJsonFileBytes);
  } catch (const std::exception& e) {
    throw ConfigError(e.what());
  }
  return parse_json_text(text, path.string());
}

Config load_config(const std::optional<std::filesystem::path>& user_file) {
  Config c = default_config();
  if (!user_file) return c;
  return apply_config_json(c, read_json_file(*user_file), user_file->string());
}

json config_to_json(const Config& c) {
  Config copy = c;
  json out = json::object();
  Writer w(out);
  w.section("road", copy.road);
  w.section("car", copy.car);
  w.section("world", copy.world);
  w.section("planner", copy.planner);
  return out;
}

std::string config_hash(const Config& c) {
  return core::hex64(core::fnv1a64(json_text(config_to_json(c))));
}

}  // namespace overtake::app
