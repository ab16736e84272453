#include "overtake/run/config.hpp"

#include <set>
#include <sstream>

#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/core/hash.hpp"
#include "overtake/core/text_check.hpp"
#include "overtake/planner/reference/assertiveness.hpp"
#include "overtake/run/resources.hpp"

namespace overtake::run {

using base::json_text;

using base::read_file;
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

namespace {

// `j`'s keys over `c`; what cannot be read goes into `errors`, naming the key.
void read_sections(Config& c, const json& j, std::vector<std::string>& errors) {
  Reader top(j, "", errors);
  top.section("road", c.road);
  top.section("car", c.car);
  top.section("world", c.world);
  top.section("planner", c.planner);
  top.check_unknown();
}

}  // namespace

Config apply_config_json(Config base, const json& j, std::string_view source) {
  if (!j.is_object()) fail(source, {"the top level must be a JSON object"});
  std::vector<std::string> errors;
  const Config before = base;
  read_sections(base, j, errors);
  if (!errors.empty()) fail(source, errors);
  // The file moved the knob: its keys move from where they stood, then the file's own keys
  // are read over them again, so that a key set by hand keeps its value.
  const double a = base.planner.reference.assertiveness;
  if (a != before.planner.reference.assertiveness && a >= 0.0 && a <= 1.0) {
    base = before;
    base.planner.reference = planner::with_assertiveness(before.planner.reference, a);
    read_sections(base, j, errors);
  }
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

namespace {

/// Builds the document as the library's own DOM builder does, and refuses a key given twice in
/// one object (the library would keep the last one, silently). A SAX handler, not a parse
/// callback: the library's callback parser scans the enclosing array's elements at the end of
/// every object, so a list of n objects took time in n^2 (200,000 scenario events: 7.6 s).
class DuplicateKeyWatch {
 public:
  explicit DuplicateKeyWatch(json& root) : dom_(root, true) {}

  bool null() { return dom_.null(); }
  bool boolean(bool v) { return dom_.boolean(v); }
  bool number_integer(json::number_integer_t v) { return dom_.number_integer(v); }
  bool number_unsigned(json::number_unsigned_t v) { return dom_.number_unsigned(v); }
  bool number_float(json::number_float_t v, const json::string_t& text) {
    return dom_.number_float(v, text);
  }
  bool string(json::string_t& v) { return dom_.string(v); }
  bool binary(json::binary_t& v) { return dom_.binary(v); }
  bool start_object(std::size_t n) {
    levels_.push_back({true, {}, {}});
    return dom_.start_object(n);
  }
  bool key(json::string_t& k) {
    if (!levels_.empty()) {
      Level& here = levels_.back();
      here.key = k;
      if (!here.keys.insert(k).second && duplicate_.empty()) {
        for (const Level& l : levels_)
          duplicate_ += l.object ? (duplicate_.empty() ? "" : ".") + l.key : "[]";
      }
    }
    return dom_.key(k);
  }
  bool end_object() {
    if (!levels_.empty()) levels_.pop_back();
    return dom_.end_object();
  }
  bool start_array(std::size_t n) {
    levels_.push_back({false, {}, {}});
    return dom_.start_array(n);
  }
  bool end_array() {
    if (!levels_.empty()) levels_.pop_back();
    return dom_.end_array();
  }
  template <class Exception>
  bool parse_error(std::size_t at, const std::string& token, const Exception& e) {
    return dom_.parse_error(at, token, e);  // throws e
  }
  /// The first key given twice, as a path ("cars[].lane"); empty when none was.
  [[nodiscard]] const std::string& duplicate() const { return duplicate_; }

 private:
  struct Level {
    bool object = false;
    std::set<std::string> keys;
    std::string key;  // the last key read at this level
  };
  nlohmann::detail::json_sax_dom_parser<json> dom_;
  std::vector<Level> levels_;
  std::string duplicate_;
};

}  // namespace

json parse_json_text(std::string_view text, std::string_view source) {
  json j;
  DuplicateKeyWatch watch(j);
  try {
    core::require_json_depth(text, source);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(e.what());
  }
  try {
    (void)json::sax_parse(text.begin(), text.end(), &watch);
  } catch (const json::exception& e) {  // parse_error; out_of_range for a number like 1e999
    throw ConfigError(std::string(source) + ": not valid JSON: " + e.what());
  }
  if (!watch.duplicate().empty()) {
    throw ConfigError(std::string(source) + ": the key '" + watch.duplicate() + "' is given twice");
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

}  // namespace overtake::run
