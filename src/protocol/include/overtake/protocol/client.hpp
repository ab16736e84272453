#pragma once
// `overtake sim --planner ws://...`: our simulator drives any planner written for the
// original, over the original protocol.
//
// IO model: the connection owns a private io_context that only the calling thread runs, in
// bounded slices (each wait has a deadline). A read is always outstanding, so frames that
// arrive unasked are noticed. Lock-step runs sim::run_drive with a PlannerFn that does one
// round trip; real time steps at 50 Hz of wall time while waiting for replies.

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
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

/// A duration as the client's messages write it, e.g. "0.3 s".
[[nodiscard]] std::string seconds_text(std::chrono::milliseconds ms);

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
  /// When set and true (Ctrl-C), a wait for the planner ends at once: the lock-step run then
  /// ends with ended_early "stopped", as the world loop ends it between cycles.
  const std::atomic<bool>* stop = nullptr;
  /// When set, makes the TCP socket of each connection attempt (a file descriptor, owned by
  /// the connection from then on; -1 when none can be made): e.g. one made inside a planner
  /// program's own network namespace. Empty: an ordinary socket of this process.
  std::function<int()> open_socket;
  /// When set, asked between connection attempts: a non-empty answer ends the attempts at
  /// once with that reason (e.g. the planner program has exited).
  std::function<std::string()> give_up;
};

/// One frame received from the peer.
struct ReceivedFrame {
  std::string text;  ///< the payload (a pong's payload when `pong`)
  bool binary = false;
  bool pong = false;  ///< a websocket pong (a control frame), in its place among the messages
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
  /// Sends a websocket ping (at most 125 bytes of payload); its pong comes back from
  /// receive() as a frame with `pong` set. Throws as send() does.
  void ping(std::string_view payload, Clock::time_point deadline);
  /// The next frame (or pong), or nullopt when none has come by `deadline`. Throws
  /// ConnectionError when the connection is lost (frames that came before are returned first).
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
/// timeout, closes the connection, sends a malformed reply, or sends more replies than it
/// was sent telemetries ("out of step"). A `manual` reply to a full telemetry keeps the
/// queued path (the PlannerFn hands it back).
///
/// Out of step. The protocol has no message ids, and a planner may send the same path twice
/// on purpose, so a reply that arrives after the next telemetry went out cannot be told from
/// a late second reply to an earlier one, neither by its content nor by its timing: taken as
/// the next reply, it would put the run one reply behind for good. So replies are counted,
/// against two bounds that hold for every planner that answers once:
/// - no more replies than telemetries sent (a reply with no telemetry waiting for it);
/// - no more than j replies before the pong of ping j: right after its j-th telemetry the
///   client sends a websocket ping whose payload is j, and every websocket library answers
///   a ping when it reads it, which is after the planner has read telemetry j and before it
///   reads telemetry j+1; by then it can have answered j telemetries at most.
/// A planner that answers in its message handler (as planners for the original do) sends
/// its reply to telemetry j before the pong j, so a second reply, whenever it is sent, is
/// found at the next pong or sooner. Nothing waits for pongs during the run (a planner with
/// Nagle's algorithm on would hold each pong until our next telemetry acknowledges its
/// reply); finish() waits for the last one, then a little longer for a copy sent from a
/// timer or another thread, or by a planner that answers pings before it answers telemetry.
class RemotePlanner {
 public:
  RemotePlanner(PlannerConnection& connection, const ClientOptions& options);
  [[nodiscard]] core::PlanResult operator()(const core::Telemetry& telemetry);
  /// After a run that went its full length: waits for the pong of the last telemetry's ping
  /// and then a little longer (twice the longest round trip, at least 0.1 s, at most the
  /// reply timeout) for any reply still on its way. Returns why the run is out of step, or
  /// "" when it is not.
  [[nodiscard]] std::string finish();
  /// True when a wait was cut short by options.stop (the run was stopped, not failed).
  [[nodiscard]] bool stopped() const { return stopped_; }

 private:
  std::optional<ReceivedFrame> receive(Clock::time_point deadline);
  void count_reply(const ReceivedFrame& frame);
  void count_pong(const std::string& payload);
  void take_unasked(const ReceivedFrame& frame, bool after_run);
  PlannerConnection& connection_;
  ClientOptions options_;
  std::string buffer_;
  long sent_ = 0;       // telemetries sent
  long replies_ = 0;    // replies received (taken or not)
  long last_pong_ = 0;  // the highest ping whose pong has come; 0: none yet
  Clock::duration longest_round_trip_{};
  bool manual_noted_ = false;
  bool stopped_ = false;
};

/// Runs `world` against the remote planner in lock-step: sim::run_drive with a
/// RemotePlanner, then RemotePlanner::finish() when the run went its full length (its
/// failure ends the run as planner_failed, as any planner failure does). A run stopped
/// through options.stop or run.stop ends as stopped. Cycles are timed as round trips.
[[nodiscard]] sim::RunReport run_lock_step(sim::World& world, PlannerConnection& connection,
                                           const ClientOptions& options, sim::RunOptions run);

/// Runs `world` against the remote planner in real time (the stepper paced at real time): a
/// step every world step_s of wall time, the queue consumed while the planner thinks, a full
/// telemetry after each reply when anything stepped since the last one and `42["telemetry",null]`
/// when nothing did (the planner's `manual` then waits for the next step). Ends early, with the
/// report so far, on a stall, a disconnect or a malformed reply. Planner time = round trip of full
/// telemetries. run.observer (when set) sees the start, every step, and each path when it arrives.
[[nodiscard]] sim::RunReport run_realtime(sim::World& world, PlannerConnection& connection,
                                          const ClientOptions& options, sim::RunOptions run);

}  // namespace overtake::protocol
