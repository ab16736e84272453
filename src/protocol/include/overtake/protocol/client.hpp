#pragma once
// `overtake sim --planner ws://...`: our simulator drives any planner written for the
// original, over the original protocol.
//
// IO model: the connection owns a private io_context that only the calling thread runs, in
// bounded slices (each wait has a deadline). A read is always outstanding, so frames that
// arrive unasked are noticed. Lock-step runs sim::run_drive with a PlannerFn that does one
// round trip; real time steps at 50 Hz of wall time while waiting for replies.

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "overtake/protocol/codec.hpp"
#include "overtake/protocol/log.hpp"
#include "overtake/sim/run.hpp"
#include "overtake/sim/world.hpp"

namespace overtake::protocol {

using Clock = std::chrono::steady_clock;

/// Where a planner listens: `ws://HOST:PORT/PATH`.
struct PlannerUrl {
  std::string host;
  std::string port = "4567";
  std::string target = "/socket.io/?EIO=4&transport=websocket";  ///< the original's, by default
};
/// Parses `ws://HOST[:PORT][/PATH]` (HOST may be `[v6]`); the path defaults to the
/// original's when the URL has none.
[[nodiscard]] Result<PlannerUrl> parse_planner_url(std::string_view url);
/// `ws://HOST:PORT/PATH`.
[[nodiscard]] std::string to_string(const PlannerUrl& url);

/// The connection failed or was lost; the message says how.
class ConnectionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// How the client waits and what it accepts.
struct ClientOptions {
  std::chrono::milliseconds connect_timeout{10'000};  ///< keep retrying the connection this long
  std::chrono::milliseconds reply_timeout{2'000};     ///< longest wait for one reply
  std::size_t max_frame_bytes = std::size_t{1} << 20;
  Limits limits;
  LogFn log;  ///< empty: stderr_log(false)
};

/// One frame received from the peer.
struct ReceivedFrame {
  std::string text;
  bool binary = false;
};

/// A websocket client connection with deadlines on everything.
class PlannerConnection {
 public:
  /// Connects with the original's upgrade request (plain RFC 6455, no subprotocol, no
  /// extensions, no Origin or cookies), retrying until options.connect_timeout has passed.
  /// Throws ConnectionError.
  PlannerConnection(const PlannerUrl& url, const ClientOptions& options);
  ~PlannerConnection();
  PlannerConnection(const PlannerConnection&) = delete;
  PlannerConnection& operator=(const PlannerConnection&) = delete;

  /// Sends one text (or binary) frame, waiting at most until `deadline`. Throws
  /// ConnectionError when the connection is lost or the frame cannot be sent in time.
  void send(std::string_view payload, Clock::time_point deadline, bool binary = false);
  /// The next frame, or nullopt when none has come by `deadline`. Throws ConnectionError when
  /// the connection is lost (frames that came before are returned first).
  [[nodiscard]] std::optional<ReceivedFrame> receive(Clock::time_point deadline);
  /// Frames that have already arrived, without waiting.
  [[nodiscard]] std::vector<ReceivedFrame> take_arrived();
  /// Sends a close frame and waits briefly for the peer's; never throws.
  void close() noexcept;
  /// True until the connection has been lost or closed.
  [[nodiscard]] bool is_open() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A remote planner as a sim::PlannerFn for lock-step runs: sends the telemetry, waits for
/// the reply. Ends the run (sim::PlannerFailure) when the planner stalls past the reply
/// timeout, closes the connection or sends a malformed reply. A `manual` reply to a full
/// telemetry keeps the queued path (the PlannerFn hands it back); replies that no telemetry
/// asked for (a planner that replied twice) are ignored with one log line each when they have
/// arrived by the time the next telemetry is sent.
class RemotePlanner {
 public:
  RemotePlanner(PlannerConnection& connection, const ClientOptions& options);
  [[nodiscard]] std::vector<core::Vec2> operator()(const core::Telemetry& telemetry);
  /// Replies ignored because no telemetry asked for them.
  [[nodiscard]] long extra_replies() const { return extra_replies_; }

 private:
  PlannerConnection& connection_;
  ClientOptions options_;
  std::string buffer_;
  long extra_replies_ = 0;
  bool manual_noted_ = false;
};

/// Runs `world` against the remote planner in real time: a step every world step_s of wall
/// time, the queue consumed while the planner thinks, a full telemetry after each reply when
/// anything stepped since the last one and `42["telemetry",null]` when nothing did (the
/// planner's `manual` then waits for the next step). Ends early, with the report so far, on a
/// stall, a disconnect or a malformed reply. Planner time = round trip of full telemetries.
/// run.observer (when set) sees the start, every step, and each path when it arrives.
[[nodiscard]] sim::RunReport run_realtime(sim::World& world, PlannerConnection& connection,
                                          const ClientOptions& options, const sim::RunOptions& run);

}  // namespace overtake::protocol
