#pragma once
// Log lines of the protocol's server and client: one line per event, to a sink the caller
// chooses (stderr for the command line, a capture in tests).

#include <functional>
#include <string_view>

namespace overtake::protocol {

/// Importance of a log line.
enum class LogLevel {
  info,     ///< connection events and status lines
  warning,  ///< a bad frame or a failure
};

/// Where log lines go (one line per call, without a newline).
using LogFn = std::function<void(LogLevel, std::string_view)>;

/// Log lines to stderr; info lines only when `verbose`.
[[nodiscard]] LogFn stderr_log(bool verbose);

}  // namespace overtake::protocol
