#pragma once
// The messages of the original simulator's protocol (design/protocol.md) as pure functions:
// text in, plain structs out, and back. No sockets. Errors are values with a reason.
//
// Simulator -> planner: `42["telemetry",{...}]` (or the null form), numbers printed as
// 32-bit floats with 7 significant digits, yaw in degrees and speed in mph on the wire.
// Planner -> simulator: `42["control",{"next_x":[...],"next_y":[...]}]` or `42["manual",{}]`.

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "overtake/core/telemetry.hpp"

namespace overtake::protocol {

/// Why a message was rejected.
struct Error {
  std::string reason;
};

/// A value, or the reason there is none (the protocol never throws for bad input).
template <class T>
class Result {
 public:
  Result(T value) : v_(std::move(value)) {}      // NOLINT(google-explicit-constructor)
  Result(Error error) : v_(std::move(error)) {}  // NOLINT(google-explicit-constructor)
  [[nodiscard]] bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }
  [[nodiscard]] const T& value() const& { return std::get<0>(v_); }
  [[nodiscard]] T& value() & { return std::get<0>(v_); }
  [[nodiscard]] T&& value() && { return std::get<0>(std::move(v_)); }
  /// The reason; only when !ok().
  [[nodiscard]] const std::string& error() const { return std::get<1>(v_).reason; }

 private:
  std::variant<T, Error> v_;
};

/// Size limits applied when parsing (ours: the original has none).
struct Limits {
  std::size_t max_path_points = 10'000;  ///< previous_path / next_x length
  std::size_t max_cars = 1'000;          ///< sensor_fusion rows
  /// Numbers larger than this in magnitude are rejected: the original prints positions with
  /// 7 significant digits, no map comes near, and absurd values only upset the geometry.
  double max_magnitude = 1e7;
};

// ---- numbers ----------------------------------------------------------------------------

/// Appends `value` as the original prints it: cast to a 32-bit float, 7 significant digits,
/// trailing zeros dropped, integers bare, C#-style exponent (`1E-05`, `1E+07`) when the
/// decimal exponent is below -4 or above 6; negative zero prints as `0`. Parsing the text
/// gives exactly core::wire_round(value) for every finite value in float range. NaN and
/// infinities print as C# does (`NaN`, `Infinity`, `-Infinity`), which is not JSON.
void append_wire_number(std::string& out, double value);
/// The text of append_wire_number.
[[nodiscard]] std::string format_wire_number(double value);
/// Appends `value` with the fewest digits that parse back to exactly the same double
/// (`-0.0` keeps its sign). Precondition: finite.
void append_exact_number(std::string& out, double value);

// ---- telemetry (simulator -> planner) ---------------------------------------------------

/// The empty telemetry, sent when nothing has advanced since the last full one.
inline constexpr std::string_view kNullTelemetry = R"(42["telemetry",null])";

/// Appends the full telemetry frame exactly as the original prints it (keys in its order,
/// no spaces, wire numbers; yaw converted to degrees, speed to mph).
void append_telemetry(std::string& out, const core::Telemetry& telemetry);
/// The text of append_telemetry.
[[nodiscard]] std::string format_telemetry(const core::Telemetry& telemetry);

/// A parsed telemetry event: the snapshot, or nullopt for `42["telemetry",null]`.
using TelemetryEvent = std::optional<core::Telemetry>;
/// Parses a telemetry frame (SI units out: degrees -> rad, mph -> m/s). Rejects anything
/// else: other events, wrong types, missing keys, non-finite numbers (strings, `null`),
/// numbers beyond the magnitude limit, paths of unequal length or longer than the limits.
[[nodiscard]] Result<TelemetryEvent> parse_telemetry(std::string_view frame,
                                                     const Limits& limits = {});

// ---- replies (planner -> simulator) -----------------------------------------------------

/// The reply to an empty telemetry: no path is applied.
inline constexpr std::string_view kManual = R"(42["manual",{}])";

/// Appends `42["control",{"next_x":[...],"next_y":[...]}]` with every coordinate written
/// exactly (append_exact_number). Precondition: all coordinates finite.
void append_control(std::string& out, std::span<const core::Vec2> path);
/// The text of append_control.
[[nodiscard]] std::string format_control(std::span<const core::Vec2> path);

/// A planner's reply: a path (`control`) or none (`manual`).
struct Reply {
  bool manual = false;
  std::vector<core::Vec2> path;  ///< empty for manual
};
/// Parses a `control` or `manual` frame as the original reads it: for every index of
/// `next_x` the same index of `next_y` (extra `next_y` entries are ignored). Rejects a
/// missing array, a shorter `next_y`, non-numbers (`null` is how planners write NaN),
/// numbers beyond the magnitude limit, and paths longer than the limit.
[[nodiscard]] Result<Reply> parse_reply(std::string_view frame, const Limits& limits = {});

// ---- framing ----------------------------------------------------------------------------

/// Engine.IO packet types (the first character of a frame).
enum class PacketType { open, close, ping, pong, message, upgrade, noop, invalid };

/// A frame split into its Engine.IO type and the rest.
struct Packet {
  PacketType type = PacketType::invalid;
  std::string_view data;  ///< after the type digit (for a message: Socket.IO type first)
};
/// Splits a text frame: `invalid` when it is empty or does not start with 0-6.
[[nodiscard]] Packet split_packet(std::string_view frame);
/// True for a Socket.IO event frame: `42` followed by anything.
[[nodiscard]] bool is_event(std::string_view frame);
/// The event name of an event frame when it can be read from its start (`42["name",`),
/// without parsing the rest; nullopt otherwise.
[[nodiscard]] std::optional<std::string_view> event_name(std::string_view frame);

/// At most `max_chars` of `text` for a log line, with control characters escaped.
[[nodiscard]] std::string excerpt(std::string_view text, std::size_t max_chars = 60);

}  // namespace overtake::protocol
