#include "overtake/protocol/codec.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <exception>
#include <system_error>

#include <nlohmann/json.hpp>

#include "overtake/core/text_check.hpp"
#include "overtake/core/units.hpp"

namespace overtake::protocol {
namespace {

using nlohmann::json;

constexpr std::string_view kEventPrefix = "42";
// Significant digits of the original's float printing (C# float.ToString()).
constexpr int kWireDigits = 7;

// A rejected message, thrown inside this file only and turned into an Error at its API.
struct Reject {
  std::string reason;
};

[[noreturn]] void reject(std::string reason) {
  throw Reject{std::move(reason)};
}

std::string quoted(std::string_view key) {
  return "'" + std::string(key) + "'";
}

// What a JSON value is, for a message that says why it is not a number.
std::string describe(const json& j) {
  switch (j.type()) {
    case json::value_t::null:
      return "null";
    case json::value_t::boolean:
      return "a boolean";
    case json::value_t::string:
      return "a string (" + excerpt(j.get_ref<const std::string&>(), 20) + ")";
    case json::value_t::array:
      return "an array";
    case json::value_t::object:
      return "an object";
    case json::value_t::binary:
      return "binary";
    case json::value_t::discarded:
      return "invalid";
    default:
      return "a number";
  }
}

// The value of a JSON number that must be finite and not absurdly large; `what()` names it
// in the error (built only then).
template <class What>
double finite_number(const json& j, double max_magnitude, const What& what) {
  if (!j.is_number()) reject(what() + " is " + describe(j) + ", not a number");
  const double v = j.get<double>();
  if (!std::isfinite(v)) reject(what() + " is not a finite number");
  if (std::abs(v) > max_magnitude) {
    char says[64];
    std::snprintf(says, sizeof says, ": %g (the limit is %g either way)", v, max_magnitude);
    reject(what() + " is out of range" + says);
  }
  return v;
}

const json& member(const json& obj, const char* key) {
  const auto it = obj.find(key);
  if (it == obj.end()) reject(quoted(key) + " is missing");
  return *it;
}

double number_member(const json& obj, const char* key, const Limits& limits) {
  return finite_number(member(obj, key), limits.max_magnitude, [key] { return quoted(key); });
}

const json& array_member(const json& obj, const char* key, std::size_t max_size, const char* unit) {
  const json& a = member(obj, key);
  if (!a.is_array()) reject(quoted(key) + " is " + describe(a) + ", not an array");
  if (a.size() > max_size) {
    reject(quoted(key) + " has " + std::to_string(a.size()) + " " + unit +
           ", more than the limit of " + std::to_string(max_size));
  }
  return a;
}

// An element of an array member, for error messages.
auto element(const char* key, std::size_t i) {
  return [key, i] { return quoted(key) + "[" + std::to_string(i) + "]"; };
}

// nlohmann's parse error without its prefix and its "last read" echo (which can be huge),
// with the column counted in the whole frame: "column 40: syntax error while parsing value -
// invalid literal".
std::string parse_error_text(std::string_view what, std::size_t offset) {
  std::string_view s = what;
  if (s.starts_with("[json.exception.")) s = s.substr(std::min(s.size(), s.find("] ") + 2));
  if (const auto at = s.find("column "); at != std::string_view::npos) {
    s = s.substr(at + 7);
    std::size_t column = 0;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), column);
    s = std::string_view(r.ptr, static_cast<std::size_t>(s.data() + s.size() - r.ptr));
    if (const auto cut = s.find("; last read"); cut != std::string_view::npos) s = s.substr(0, cut);
    return "column " + std::to_string(column + offset) + std::string(s);
  }
  return std::string(s.substr(0, 120));
}

// The JSON array `[name, payload]` of an event frame.
json parse_event(std::string_view frame) {
  if (frame.substr(0, kEventPrefix.size()) != kEventPrefix) {
    reject("not a Socket.IO event (does not start with 42): " + excerpt(frame));
  }
  const std::string_view body = frame.substr(kEventPrefix.size());
  if (const auto at = core::json_too_deep_at(body)) {
    reject("the event nests arrays and objects deeper than " + std::to_string(core::kMaxJsonDepth) +
           " levels (at column " + std::to_string(*at + kEventPrefix.size()) + ")");
  }
  json j;
  try {
    j = json::parse(body.begin(), body.end());
  } catch (const json::exception& e) {  // parse_error, or out_of_range for 1e999
    reject("the event is not valid JSON (" + parse_error_text(e.what(), kEventPrefix.size()) +
           "): " + excerpt(frame));
  }
  if (!j.is_array() || j.size() != 2)
    reject("the event is not a [name, payload] array: " + excerpt(frame));
  if (!j[0].is_string()) reject("the event name is " + describe(j[0]) + ", not a string");
  return j;
}

core::Telemetry telemetry_from_json(const json& o, const Limits& limits) {
  const double max = limits.max_magnitude;
  core::Telemetry t;
  t.ego.position = {number_member(o, "x", limits), number_member(o, "y", limits)};
  t.ego.yaw_rad = core::deg_to_rad(number_member(o, "yaw", limits));
  t.ego.speed_mps = core::mph_to_mps(number_member(o, "speed", limits));
  t.ego.s_m = number_member(o, "s", limits);
  t.ego.d_m = number_member(o, "d", limits);

  const json& px = array_member(o, "previous_path_x", limits.max_path_points, "points");
  const json& py = array_member(o, "previous_path_y", limits.max_path_points, "points");
  if (px.size() != py.size()) {
    reject("'previous_path_x' has " + std::to_string(px.size()) +
           " points but 'previous_path_y' has " + std::to_string(py.size()));
  }
  t.previous_path.resize(px.size());
  for (std::size_t i = 0; i < px.size(); ++i) {
    t.previous_path[i] = {finite_number(px[i], max, element("previous_path_x", i)),
                          finite_number(py[i], max, element("previous_path_y", i))};
  }
  t.end_path = {number_member(o, "end_path_s", limits), number_member(o, "end_path_d", limits)};

  const json& fusion = array_member(o, "sensor_fusion", limits.max_cars, "cars");
  t.cars.resize(fusion.size());
  for (std::size_t i = 0; i < fusion.size(); ++i) {
    const json& row = fusion[i];
    const auto where = element("sensor_fusion", i);
    if (!row.is_array()) reject(where() + " is " + describe(row) + ", not an array");
    if (row.size() != 7) {
      reject(where() + " has " + std::to_string(row.size()) +
             " values, expected 7 [id,x,y,vx,vy,s,d]");
    }
    double v[7];
    for (std::size_t k = 0; k < 7; ++k) {
      v[k] = finite_number(row[k], max, [&] { return where() + "[" + std::to_string(k) + "]"; });
    }
    if (v[0] != std::floor(v[0])) reject(where() + ": the id is not an integer");
    t.cars[i] = core::car_from_row(v);
  }
  return t;
}

std::vector<core::Vec2> path_from_json(const json& o, const Limits& limits) {
  const json& xs = array_member(o, "next_x", limits.max_path_points, "points");
  const auto ys_it = o.find("next_y");
  if (ys_it == o.end()) reject("'next_y' is missing");
  const json& ys = *ys_it;
  if (!ys.is_array()) reject("'next_y' is " + describe(ys) + ", not an array");
  if (ys.size() < xs.size()) {
    reject("'next_y' has " + std::to_string(ys.size()) + " points, fewer than the " +
           std::to_string(xs.size()) + " of 'next_x'");
  }
  // The original reads each coordinate as a 32-bit float; the magnitude limit is far inside
  // its range.
  std::vector<core::Vec2> path(xs.size());
  for (std::size_t i = 0; i < xs.size(); ++i) {
    path[i] = {finite_number(xs[i], limits.max_magnitude, element("next_x", i)),
               finite_number(ys[i], limits.max_magnitude, element("next_y", i))};
  }
  return path;
}

template <class T, class F>
Result<T> guarded(F&& f) {
  try {
    return f();
  } catch (const Reject& r) {
    return Error{r.reason};
  } catch (const std::exception& e) {  // e.g. out of memory on a huge message
    return Error{std::string("cannot read the message: ") + e.what()};
  }
}

}  // namespace

// ---- numbers ----------------------------------------------------------------------------

void append_wire_number(std::string& out, double value) {
  const auto f = static_cast<float>(value);
  if (std::isnan(f)) {
    out += "NaN";
    return;
  }
  if (std::isinf(f)) {
    out += f > 0 ? "Infinity" : "-Infinity";
    return;
  }
  if (f == 0.0f) {  // C# (Mono) prints negative zero as 0
    out += '0';
    return;
  }
  // printf's %.7g rule is C#'s G7 rule (fixed notation for decimal exponents -5 < e < 7);
  // only the exponent's letter differs.
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, f, std::chars_format::general, kWireDigits);
  for (char* p = buf; p != r.ptr; ++p) {
    if (*p == 'e') *p = 'E';
  }
  out.append(buf, r.ptr);
}

std::string format_wire_number(double value) {
  std::string s;
  append_wire_number(s, value);
  return s;
}

void append_exact_number(std::string& out, double value) {
  if (value == 0.0 && std::signbit(value)) {
    out += "-0.0";  // "-0" would be read back as the integer 0
    return;
  }
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, value);
  out.append(buf, r.ptr);
}

// ---- telemetry --------------------------------------------------------------------------

void append_telemetry(std::string& out, const core::Telemetry& t) {
  const auto num = [&out](double v) { append_wire_number(out, v); };
  out.reserve(out.size() + 256 + 24 * t.previous_path.size() + 80 * t.cars.size());
  out += R"(42["telemetry",{"x":)";
  num(t.ego.position.x);
  out += R"(,"y":)";
  num(t.ego.position.y);
  out += R"(,"yaw":)";
  num(core::rad_to_deg(t.ego.yaw_rad));
  out += R"(,"speed":)";
  num(core::mps_to_mph(t.ego.speed_mps));
  out += R"(,"s":)";
  num(t.ego.s_m);
  out += R"(,"d":)";
  num(t.ego.d_m);
  out += R"(,"previous_path_x":[)";
  for (std::size_t i = 0; i < t.previous_path.size(); ++i) {
    if (i) out += ',';
    num(t.previous_path[i].x);
  }
  out += R"(],"previous_path_y":[)";
  for (std::size_t i = 0; i < t.previous_path.size(); ++i) {
    if (i) out += ',';
    num(t.previous_path[i].y);
  }
  out += R"(],"end_path_s":)";
  num(t.end_path.s_m);
  out += R"(,"end_path_d":)";
  num(t.end_path.d_m);
  out += R"(,"sensor_fusion":[)";
  for (std::size_t i = 0; i < t.cars.size(); ++i) {
    const core::CarObservation& c = t.cars[i];
    out += i ? ",[" : "[";
    char id[16];
    out.append(id, std::to_chars(id, id + sizeof id, c.id).ptr);
    for (const double v :
         {c.position.x, c.position.y, c.velocity_mps.x, c.velocity_mps.y, c.s_m, c.d_m}) {
      out += ',';
      num(v);
    }
    out += ']';
  }
  out += "]}]";
}

std::string format_telemetry(const core::Telemetry& telemetry) {
  std::string s;
  append_telemetry(s, telemetry);
  return s;
}

Result<TelemetryEvent> parse_telemetry(std::string_view frame, const Limits& limits) {
  return guarded<TelemetryEvent>([&]() -> TelemetryEvent {
    const json event = parse_event(frame);
    const auto& name = event[0].get_ref<const std::string&>();
    if (name != "telemetry") reject("unexpected event " + excerpt(name) + " (expected telemetry)");
    const json& payload = event[1];
    if (payload.is_null()) return std::nullopt;
    if (!payload.is_object())
      reject("the telemetry payload is " + describe(payload) + ", not an object");
    return telemetry_from_json(payload, limits);
  });
}

// ---- replies ----------------------------------------------------------------------------

void append_control(std::string& out, std::span<const core::Vec2> path) {
  out.reserve(out.size() + 48 + 44 * path.size());
  out += R"(42["control",{"next_x":[)";
  for (std::size_t i = 0; i < path.size(); ++i) {
    if (i) out += ',';
    append_exact_number(out, path[i].x);
  }
  out += R"(],"next_y":[)";
  for (std::size_t i = 0; i < path.size(); ++i) {
    if (i) out += ',';
    append_exact_number(out, path[i].y);
  }
  out += "]}]";
}

std::string format_control(std::span<const core::Vec2> path) {
  std::string s;
  append_control(s, path);
  return s;
}

Result<Reply> parse_reply(std::string_view frame, const Limits& limits) {
  return guarded<Reply>([&]() -> Reply {
    const json event = parse_event(frame);
    const auto& name = event[0].get_ref<const std::string&>();
    if (name == "manual") return Reply{true, {}};
    if (name != "control")
      reject("unexpected event " + excerpt(name) + " (expected control or manual)");
    const json& payload = event[1];
    if (!payload.is_object())
      reject("the control payload is " + describe(payload) + ", not an object");
    return Reply{false, path_from_json(payload, limits)};
  });
}

// ---- framing ----------------------------------------------------------------------------

Packet split_packet(std::string_view frame) {
  if (frame.empty() || frame[0] < '0' || frame[0] > '6') return {PacketType::invalid, frame};
  return {static_cast<PacketType>(frame[0] - '0'), frame.substr(1)};
}

bool is_event(std::string_view frame) {
  return frame.substr(0, kEventPrefix.size()) == kEventPrefix;
}

std::optional<std::string_view> event_name(std::string_view frame) {
  constexpr std::string_view kStart = R"(42[")";
  if (frame.substr(0, kStart.size()) != kStart) return std::nullopt;
  const std::string_view rest = frame.substr(kStart.size());
  const auto end = rest.find_first_of("\"\\");
  if (end == std::string_view::npos || rest[end] != '"') return std::nullopt;
  if (end + 1 < rest.size() && rest[end + 1] != ',' && rest[end + 1] != ']') return std::nullopt;
  return rest.substr(0, end);
}

std::string excerpt(std::string_view text, std::size_t max_chars) {
  std::string out = "\"";
  const std::size_t n = std::min(text.size(), max_chars);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20 || c >= 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    } else {
      out += static_cast<char>(c);
    }
  }
  out += '"';
  if (n < text.size()) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

}  // namespace overtake::protocol
