#pragma once
// `overtake serve`: our planners behind the original protocol, so that the original
// simulator (or `overtake sim --planner`) can drive them.
//
// IO model: one io_context, run by run_server on the calling thread. Each connection is a
// coroutine on it with its own PlannerSession (its own policy instance); the planner runs
// inline on that thread, so connections are served in turn, one frame at a time. Nothing a
// peer sends ends the server: every bad frame gets one log line and, when the simulator is
// waiting for an answer, `manual`.

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "overtake/core/reference_line.hpp"
#include "overtake/core/telemetry.hpp"
#include "overtake/planner/params.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/protocol/codec.hpp"
#include "overtake/protocol/log.hpp"

namespace boost::asio {
class io_context;
}  // namespace boost::asio

namespace overtake::protocol {

/// One websocket message as it came off the socket.
struct Frame {
  std::string_view text;  ///< the payload (only its first bytes when `oversized`)
  bool binary = false;
  bool oversized = false;
  std::size_t size = 0;  ///< full size in bytes
};

/// What answering one frame produced.
struct FrameOutcome {
  std::optional<std::string> reply;         ///< the frame to send back, if any
  std::optional<std::string> warning;       ///< one line: what was wrong with the frame
  std::optional<std::string> note;          ///< one line of information (e.g. the simulator quit)
  bool planned = false;                     ///< the planner ran and `reply` is its control
  double plan_us = 0.0;                     ///< planner time when it ran
  std::optional<core::EgoObservation> ego;  ///< from a full telemetry, for status lines
};

/// The planner side of one connection: one policy instance and the rules for answering
/// each kind of frame (see the table in tests/protocol/server_test.cpp and the report of
/// the protocol issue):
/// - full telemetry: `control` with the policy's path;
/// - `42["telemetry",null]`: `manual`;
/// - a `42` frame that is, or may be, a telemetry but cannot be used: one warning, `manual`;
/// - `2`: `3` (Engine.IO pong); `3`, `0...`, `40`, `41`, `1`, `5`, `6`: no reply, a note;
/// - any other event, binary or non-Engine.IO frames: one warning, no reply.
class PlannerSession {
 public:
  PlannerSession(std::unique_ptr<planner::Policy> policy, const Limits& limits,
                 std::size_t max_frame_bytes);
  /// The answer to one frame. Never throws for anything in the frame.
  [[nodiscard]] FrameOutcome handle(const Frame& frame);

 private:
  FrameOutcome handle_event(std::string_view text);
  std::unique_ptr<planner::Policy> policy_;
  Limits limits_;
  std::size_t max_frame_bytes_;
};

/// What the server plans with.
struct PlannerSetup {
  std::shared_ptr<const core::ReferenceLine> line;  ///< shared: sessions may outlive the caller
  planner::PlannerParams params;
  std::string policy =
      "walkthrough";  ///< a name from planner::list_policies(), or the label of `factory`
  /// When set, makes each connection's policy (a plugin's, a Python planner's) instead of the
  /// built-in policy named `policy`.
  planner::PolicyFactory factory;
};

/// Options of `overtake serve`.
struct ServeOptions {
  std::string host = "127.0.0.1";  ///< the original's planners listen everywhere; we do not
  std::uint16_t port = 4567;       ///< 0: any free port (reported to on_listening)
  std::size_t max_frame_bytes = std::size_t{1} << 20;
  Limits limits;
  bool status_lines = true;  ///< one status line a second while connections are open
  std::chrono::milliseconds handshake_timeout{10'000};
  LogFn log;  ///< empty: stderr_log(true)
};

/// Listens on opts.host:opts.port and serves on `ioc`, running it on the calling thread until
/// it is stopped (ioc.stop(), from any thread). `on_listening` gets the bound port once the
/// socket listens. Throws std::invalid_argument for an unknown policy and std::runtime_error
/// when it cannot listen. Everything the server keeps lives in the handlers queued on `ioc`;
/// destroying `ioc` releases it.
void run_server(boost::asio::io_context& ioc, const PlannerSetup& setup, const ServeOptions& opts,
                const std::function<void(std::uint16_t port)>& on_listening = {});

/// run_server on a context of its own, until `stop` is set (looked at every 50 ms: a planner
/// that hangs in the serving thread does not delay it; `on_stop` is called then) or the server
/// ends. Throws what run_server throws.
void serve_until(const PlannerSetup& setup, const ServeOptions& opts, const std::atomic<bool>& stop,
                 const std::function<void()>& on_stop = {});

}  // namespace overtake::protocol
