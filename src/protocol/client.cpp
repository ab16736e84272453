// The simulator's side of the protocol: a websocket client with deadlines, the lock-step
// PlannerFn and the real-time loop.

#include "overtake/protocol/client.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <deque>
#include <thread>

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>

// GCC 12 may report a false maybe-uninitialized inside Beast's HTTP parser (boost::optional)
// depending on inlining (seen with the sanitizers).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/asio/connect.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#pragma GCC diagnostic pop

namespace overtake::protocol {
namespace {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;
using beast::error_code;

constexpr auto kRetryDelay = std::chrono::milliseconds(100);
constexpr auto kAttemptTimeout = std::chrono::seconds(2);
constexpr auto kCloseTimeout = std::chrono::milliseconds(500);
// How often a wait for the planner looks at the stop flag (Ctrl-C).
constexpr auto kStopPoll = std::chrono::milliseconds(50);
// The least time finish() waits for a late reply after the run.
constexpr auto kLateReplyWait = std::chrono::milliseconds(100);
constexpr const char* kOutOfStep = "out of step: the planner replied twice to one telemetry";

std::string seconds_text(std::chrono::milliseconds ms) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g s", static_cast<double>(ms.count()) / 1000.0);
  return buf;
}

}  // namespace

// ---- URL --------------------------------------------------------------------------------

Result<PlannerUrl> parse_planner_url(std::string_view url) {
  const auto lower_prefix = [&](std::string_view prefix) {
    if (url.size() < prefix.size()) return false;
    for (std::size_t i = 0; i < prefix.size(); ++i) {
      if (std::tolower(static_cast<unsigned char>(url[i])) != prefix[i]) return false;
    }
    return true;
  };
  if (lower_prefix("wss://")) return Error{"wss:// (TLS) is not supported; use ws://"};
  if (!lower_prefix("ws://")) return Error{"expected ws://HOST:PORT/..., got " + excerpt(url)};
  std::string_view rest = url.substr(5);
  PlannerUrl out;
  if (!rest.empty() && rest[0] == '[') {
    const auto close = rest.find(']');
    if (close == std::string_view::npos)
      return Error{"unclosed '[' in the host of " + excerpt(url)};
    out.host = std::string(rest.substr(1, close - 1));
    rest = rest.substr(close + 1);
  } else {
    const auto end = rest.find_first_of(":/?");
    out.host = std::string(rest.substr(0, end));
    rest = end == std::string_view::npos ? std::string_view{} : rest.substr(end);
  }
  if (out.host.empty()) return Error{"no host in " + excerpt(url)};
  if (!rest.empty() && rest[0] == ':') {
    const auto end = rest.find_first_of("/?");
    const std::string_view port = rest.substr(1, end == std::string_view::npos ? end : end - 1);
    unsigned value = 0;
    const auto r = std::from_chars(port.data(), port.data() + port.size(), value);
    if (port.empty() || r.ec != std::errc{} || r.ptr != port.data() + port.size() || value == 0 ||
        value > 65535) {
      return Error{"bad port " + excerpt(port) + " in " + excerpt(url)};
    }
    out.port = std::string(port);
    rest = end == std::string_view::npos ? std::string_view{} : rest.substr(end);
  }
  if (!rest.empty()) out.target = rest[0] == '?' ? "/" + std::string(rest) : std::string(rest);
  return out;
}

std::string to_string(const PlannerUrl& url) {
  const bool v6 = url.host.find(':') != std::string::npos;
  return "ws://" + (v6 ? "[" + url.host + "]" : url.host) + ":" + url.port + url.target;
}

// ---- connection -------------------------------------------------------------------------

struct PlannerConnection::Impl {
  net::io_context ioc;  // first: destroyed last, after everything its handlers refer to
  ClientOptions opts;
  std::unique_ptr<websocket::stream<tcp::socket>> ws;
  beast::flat_buffer rd;
  std::deque<ReceivedFrame> frames;
  std::string out;
  websocket::ping_data ping_payload;
  error_code read_error;
  // The planner's close frame, once one came. Tearing the connection down after it may then
  // fail (the planner may be gone before our close frame reaches it) and that error, not
  // `closed`, ends the read: this is what says that the planner closed.
  std::optional<websocket::close_reason> peer_close;
  bool reading = false;
  bool writing = false;
  bool open = false;

  // Runs one write (a frame or a ping) started by `start(handler)` to its end, or throws
  // ConnectionError when it fails or is not done by the deadline.
  template <class Start>
  void write(const Start& start, Clock::time_point deadline) {
    if (!open) throw ConnectionError(lost_reason());
    writing = true;
    error_code ec;
    start([this, &ec](const error_code& e, auto&&...) {
      ec = e;
      writing = false;
    });
    if (!run_until([&] { return !writing; }, deadline)) {
      drop();
      run_until([&] { return !writing; }, Clock::now() + kCloseTimeout);
      throw ConnectionError("the planner does not read: a frame could not be sent in time");
    }
    if (ec) {
      if (!read_error) read_error = ec;
      drop();
      throw ConnectionError(lost_reason());
    }
  }

  // Runs handlers until `done()` or the deadline; returns done().
  template <class Done>
  bool run_until(const Done& done, Clock::time_point deadline) {
    while (!done()) {
      if (ioc.stopped()) ioc.restart();
      if (ioc.run_one_until(deadline) == 0) {
        if (Clock::now() >= deadline || ioc.stopped()) return done();  // late, or nothing pending
      }
    }
    return true;
  }

  // Acknowledges what has arrived at once instead of up to 40 ms later. Each lock-step cycle
  // now brings two frames from the planner (its reply, then the pong of our ping); a planner
  // with Nagle's algorithm on (no TCP_NODELAY) holds the second of two small writes until the
  // first is acknowledged, and with nothing to send while it waits for a reply, the kernel
  // would delay that acknowledgement: 20-40 ms a cycle instead of microseconds. Linux leaves
  // quick-ack mode by itself, so this is set again after every read.
  void quickack() {
#ifdef TCP_QUICKACK
    const int one = 1;
    (void)::setsockopt(ws->next_layer().native_handle(), IPPROTO_TCP, TCP_QUICKACK, &one,
                       sizeof one);
#endif
  }

  void start_read() {
    reading = true;
    ws->async_read(rd, [this](const error_code& ec, std::size_t) {
      reading = false;
      quickack();
      if (ec) {
        read_error = ec;
        open = false;
        return;
      }
      frames.push_back({beast::buffers_to_string(rd.data()), ws->got_binary()});
      rd.clear();
      start_read();
    });
  }

  void drop() {
    open = false;
    if (ws) {
      error_code ignored;
      ws->next_layer().close(ignored);
    }
  }

  [[nodiscard]] std::string lost_reason() const {
    const error_code& ec = read_error;
    if (peer_close) {
      const auto code = static_cast<unsigned>(peer_close->code);
      if (peer_close->code == websocket::close_code::none)
        return "the planner closed the connection (a close frame without a code)";
      std::string why =
          peer_close->code == websocket::close_code::normal
              ? "the planner closed the connection normally (close code 1000"
              : "the planner closed the connection (close code " + std::to_string(code);
      if (!peer_close->reason.empty()) {
        why +=
            ": " + excerpt(std::string_view(peer_close->reason.data(), peer_close->reason.size()));
      }
      return why + ")";
    }
    if (ec == websocket::error::closed) return "the planner closed the connection";
    if (ec == websocket::error::message_too_big) {
      return "the planner sent a frame larger than " + std::to_string(opts.max_frame_bytes) +
             " bytes";
    }
    if (ec == net::error::eof || ec == net::error::connection_reset ||
        ec == net::error::broken_pipe) {
      return "the planner dropped the connection (" + ec.message() + ")";
    }
    if (!ec) return "the connection is closed";
    return "the connection to the planner failed (" + ec.message() + ")";
  }

  // One attempt: TCP connect and the upgrade. Returns an empty string or why it failed.
  std::string attempt(const PlannerUrl& url, Clock::time_point deadline) {
    error_code ec;
    tcp::resolver resolver(ioc);
    const auto endpoints = resolver.resolve(url.host, url.port, ec);
    if (ec) return "cannot resolve " + url.host + " (" + ec.message() + ")";

    ws = std::make_unique<websocket::stream<tcp::socket>>(ioc);
    bool done = false;
    net::async_connect(ws->next_layer(), endpoints, [&](const error_code& e, const tcp::endpoint&) {
      ec = e;
      done = true;
    });
    if (!run_until([&] { return done; }, deadline)) {
      drop();
      run_until([&] { return done; }, Clock::now() + kCloseTimeout);
      return "connecting timed out";
    }
    if (ec) return ec.message();
    ws->next_layer().set_option(tcp::no_delay(true), ec);

    // The original's request: no User-Agent, Origin, cookies, subprotocol or extensions.
    ws->set_option(websocket::permessage_deflate{});
    ws->set_option(websocket::stream_base::decorator(
        [](websocket::request_type& req) { req.erase(beast::http::field::user_agent); }));
    ws->read_message_max(opts.max_frame_bytes);
    ws->auto_fragment(false);
    // Pongs join the frames in the order they came (the lock-step client counts replies
    // against them, see RemotePlanner); a close frame is noted for lost_reason().
    ws->control_callback([this](websocket::frame_type kind, beast::string_view payload) {
      if (kind == websocket::frame_type::pong) {
        quickack();
        frames.push_back({std::string(payload.data(), payload.size()), false, true});
      } else if (kind == websocket::frame_type::close) {
        peer_close = ws->reason();
      }
    });
    done = false;
    const std::string host =
        (url.host.find(':') != std::string::npos ? "[" + url.host + "]" : url.host) + ":" +
        url.port;
    ws->async_handshake(host, url.target, [&](const error_code& e) {
      ec = e;
      done = true;
    });
    if (!run_until([&] { return done; }, deadline)) {
      drop();
      run_until([&] { return done; }, Clock::now() + kCloseTimeout);
      return "the websocket upgrade timed out";
    }
    if (ec) {
      drop();
      return "the websocket upgrade failed (" + ec.message() + ")";
    }
    open = true;
    start_read();
    return {};
  }
};

PlannerConnection::PlannerConnection(const PlannerUrl& url, const ClientOptions& options)
    : impl_(std::make_unique<Impl>()) {
  impl_->opts = options;
  const auto deadline = Clock::now() + options.connect_timeout;
  for (;;) {
    const auto attempt_deadline = std::min(deadline, Clock::now() + kAttemptTimeout);
    const std::string why = impl_->attempt(url, attempt_deadline);
    if (why.empty()) return;
    if (Clock::now() + kRetryDelay >= deadline) {
      throw ConnectionError("cannot connect to the planner at " + to_string(url) + " within " +
                            seconds_text(options.connect_timeout) + ": " + why);
    }
    std::this_thread::sleep_for(kRetryDelay);
  }
}

PlannerConnection::~PlannerConnection() {
  impl_->drop();
}

void PlannerConnection::send(std::string_view payload, Clock::time_point deadline, bool binary) {
  Impl& m = *impl_;
  m.write(
      [&](auto handler) {
        m.out.assign(payload);
        m.ws->binary(binary);
        m.ws->async_write(net::buffer(m.out), std::move(handler));
      },
      deadline);
}

void PlannerConnection::ping(std::string_view payload, Clock::time_point deadline) {
  Impl& m = *impl_;
  m.write(
      [&](auto handler) {
        m.ping_payload.assign(payload.data(), std::min(payload.size(), m.ping_payload.max_size()));
        m.ws->async_ping(m.ping_payload, std::move(handler));
      },
      deadline);
}

std::optional<ReceivedFrame> PlannerConnection::receive(Clock::time_point deadline) {
  Impl& m = *impl_;
  m.run_until([&] { return !m.frames.empty() || !m.reading; }, deadline);
  if (!m.frames.empty()) {
    ReceivedFrame f = std::move(m.frames.front());
    m.frames.pop_front();
    return f;
  }
  if (!m.reading) throw ConnectionError(m.lost_reason());
  return std::nullopt;
}

std::vector<ReceivedFrame> PlannerConnection::take_arrived() {
  Impl& m = *impl_;
  if (m.ioc.stopped()) m.ioc.restart();
  m.ioc.poll();
  std::vector<ReceivedFrame> out(std::make_move_iterator(m.frames.begin()),
                                 std::make_move_iterator(m.frames.end()));
  m.frames.clear();
  return out;
}

void PlannerConnection::close() noexcept {
  Impl& m = *impl_;
  try {
    if (m.open && !m.writing) {
      bool done = false;
      m.ws->async_close(websocket::close_code::normal, [&done](const error_code&) { done = true; });
      m.run_until([&] { return done && !m.reading; }, Clock::now() + kCloseTimeout);
    }
  } catch (...) {  // closing is best effort
  }
  m.drop();
}

bool PlannerConnection::is_open() const {
  return impl_->open;
}

// ---- what the planner sent --------------------------------------------------------------

namespace {

// A frame from the planner, sorted.
struct Sorted {
  enum Kind { reply, ping, pong, ignore, fatal } kind = ignore;
  std::string text;  // reply: the frame; ping: the pong to send; pong: its payload;
                     // ignore: a note; fatal: why
};

Sorted sort_planner_frame(const ReceivedFrame& f) {
  if (f.pong) return {Sorted::pong, f.text};
  if (f.binary) {
    return {Sorted::fatal,
            "malformed reply: a binary frame of " + std::to_string(f.text.size()) + " bytes"};
  }
  const Packet p = split_packet(f.text);
  switch (p.type) {
    case PacketType::invalid:
      return {Sorted::fatal, "malformed reply: not an Engine.IO packet: " + excerpt(f.text)};
    case PacketType::ping:
      return {Sorted::ping, "3" + std::string(p.data)};
    case PacketType::close:
      return {Sorted::fatal, "the planner closed its session (1)"};
    case PacketType::pong:
    case PacketType::open:
    case PacketType::upgrade:
    case PacketType::noop:
      return {Sorted::ignore, "ignored a packet from the planner: " + excerpt(f.text)};
    case PacketType::message:
      break;
  }
  if (!p.data.empty() && p.data[0] == '2') return {Sorted::reply, f.text};
  if (!p.data.empty() && p.data[0] == '0')
    return {Sorted::ignore, "ignored the planner's Socket.IO connect (40)"};
  if (!p.data.empty() && p.data[0] == '1') return {Sorted::fatal, "the planner left (41)"};
  return {Sorted::fatal, "malformed reply: not a Socket.IO event: " + excerpt(f.text)};
}

const LogFn& log_of(const ClientOptions& o) {
  static const LogFn fallback = stderr_log(false);
  return o.log ? o.log : fallback;
}

}  // namespace

// ---- lock-step --------------------------------------------------------------------------

RemotePlanner::RemotePlanner(PlannerConnection& connection, const ClientOptions& options)
    : connection_(connection), options_(options) {}

// The next frame by `deadline`, looking at the stop flag now and then (a signal does not
// interrupt the wait itself).
std::optional<ReceivedFrame> RemotePlanner::receive(Clock::time_point deadline) {
  for (;;) {
    if (options_.stop && options_.stop->load(std::memory_order_relaxed)) {
      stopped_ = true;
      throw sim::PlannerFailure("stopped");
    }
    auto frame = connection_.receive(std::min(deadline, Clock::now() + kStopPoll));
    if (frame || Clock::now() >= deadline) return frame;
  }
}

// The bounds on the number of replies (see RemotePlanner in the header).
void RemotePlanner::count_reply(const ReceivedFrame& f) {
  ++replies_;
  if (replies_ > sent_) {
    throw sim::PlannerFailure(std::string(kOutOfStep) + " (" + std::to_string(replies_) +
                              " replies to " + std::to_string(sent_) +
                              " telemetries; the last: " + excerpt(f.text, 40) + ")");
  }
}

void RemotePlanner::count_pong(const std::string& payload) {
  long j = 0;
  const auto r = std::from_chars(payload.data(), payload.data() + payload.size(), j);
  if (r.ec != std::errc{} || r.ptr != payload.data() + payload.size() || j < 1 || j > sent_)
    return;  // not one of ours: an unasked pong (a heartbeat) is allowed
  last_pong_ = std::max(last_pong_, j);
  if (replies_ > j) {
    throw sim::PlannerFailure(std::string(kOutOfStep) + " (" + std::to_string(replies_) +
                              " replies came before its pong to the ping that followed telemetry " +
                              std::to_string(j) + ")");
  }
}

// A frame that came while no telemetry was waiting for its reply.
void RemotePlanner::take_unasked(const ReceivedFrame& f, bool after_run) {
  const Sorted s = sort_planner_frame(f);
  switch (s.kind) {
    case Sorted::reply:
      count_reply(f);
      return;
    case Sorted::pong:
      count_pong(s.text);
      return;
    case Sorted::ping:
      if (!after_run) connection_.send(s.text, Clock::now() + options_.reply_timeout);
      return;
    case Sorted::ignore:
      log_of(options_)(LogLevel::info, s.text);
      return;
    case Sorted::fatal:
      if (!after_run) throw sim::PlannerFailure(s.text);
      log_of(options_)(LogLevel::info, "after the run: " + s.text);
      return;
  }
}

core::PlanResult RemotePlanner::operator()(const core::Telemetry& telemetry) {
  const LogFn& log = log_of(options_);
  try {
    // Anything that came in since the last reply was not asked for.
    for (const ReceivedFrame& f : connection_.take_arrived()) take_unasked(f, false);

    buffer_.clear();
    append_telemetry(buffer_, telemetry);
    const auto sent_at = Clock::now();
    const auto deadline = sent_at + options_.reply_timeout;
    connection_.send(buffer_, deadline);
    ++sent_;
    connection_.ping(std::to_string(sent_), deadline);
    for (;;) {
      const auto frame = receive(deadline);
      if (!frame) {
        throw sim::PlannerFailure("the planner stalled: no reply within " +
                                  seconds_text(options_.reply_timeout));
      }
      const Sorted s = sort_planner_frame(*frame);
      if (s.kind == Sorted::fatal) throw sim::PlannerFailure(s.text);
      if (s.kind == Sorted::pong) {
        count_pong(s.text);
        continue;
      }
      if (s.kind == Sorted::ignore) {
        log(LogLevel::info, s.text);
        continue;
      }
      if (s.kind == Sorted::ping) {
        connection_.send(s.text, deadline);
        continue;
      }
      count_reply(*frame);
      longest_round_trip_ = std::max(longest_round_trip_, Clock::now() - sent_at);
      auto reply = parse_reply(frame->text, options_.limits);
      if (!reply) throw sim::PlannerFailure("malformed reply: " + reply.error());
      if (reply.value().manual) {
        if (!manual_noted_) {
          log(LogLevel::info,
              "the planner answered a full telemetry with manual: the queued path is kept");
          manual_noted_ = true;
        }
        return core::normal_plan(telemetry.previous_path);
      }
      return core::normal_plan(std::move(reply).value().path);
    }
  } catch (const ConnectionError& e) {
    throw sim::PlannerFailure(e.what());
  }
}

std::string RemotePlanner::finish() {
  if (sent_ == 0) return {};
  try {
    for (const ReceivedFrame& f : connection_.take_arrived()) take_unasked(f, true);
    // The last pong says what the planner had sent when it read the last telemetry.
    const auto deadline = Clock::now() + options_.reply_timeout;
    while (last_pong_ < sent_) {
      const auto frame = receive(deadline);
      if (!frame) {
        log_of(options_)(LogLevel::warning,
                         "the planner did not answer our last websocket ping (RFC 6455 requires "
                         "a pong): a second reply to one telemetry may have gone unnoticed");
        break;
      }
      take_unasked(*frame, true);
    }
    // A copy sent from a timer or another thread may come after the last pong.
    const auto wait = std::min<Clock::duration>(
        options_.reply_timeout, std::max<Clock::duration>(kLateReplyWait, 2 * longest_round_trip_));
    const auto until = Clock::now() + wait;
    while (const auto frame = receive(until)) take_unasked(*frame, true);
  } catch (const sim::PlannerFailure& e) {
    return stopped_ ? std::string() : std::string(e.what());
  } catch (const ConnectionError&) {  // gone after the run: nothing more can come
  }
  return {};
}

sim::RunReport run_lock_step(sim::World& world, PlannerConnection& connection,
                             const ClientOptions& options, sim::RunOptions run) {
  RemotePlanner remote(connection, options);
  run.clock = sim::CycleClock::round_trip;
  sim::RunReport report = sim::run_drive(
      world, [&remote](const core::Telemetry& t) { return remote(t); }, run);
  if (report.outcome.end == sim::RunEnd::completed) {
    const std::string why = remote.finish();
    if (!why.empty()) report.outcome = {sim::RunEnd::planner_failed, world.time_s(), why};
  }
  return report;
}

// ---- real time --------------------------------------------------------------------------

sim::RunReport run_realtime(sim::World& world, PlannerConnection& connection,
                            const ClientOptions& options, sim::RunOptions run_options) {
  const LogFn& log = log_of(options);
  run_options.pace = sim::Pace::real_time;
  run_options.clock = sim::CycleClock::round_trip;
  sim::Stepper run(world, run_options);

  std::string buffer;
  bool awaiting = false;       // a telemetry is out and unanswered
  bool awaiting_full = false;  // ... and it was a full one
  long last_full_step = -1;
  Clock::time_point sent_at;

  const auto send_telemetry = [&](bool full) {
    sent_at = Clock::now();
    if (full) {
      buffer.clear();
      append_telemetry(buffer, run.telemetry());
      last_full_step = world.steps();
    }
    connection.send(full ? std::string_view(buffer) : kNullTelemetry,
                    sent_at + options.reply_timeout);
    awaiting = true;
    awaiting_full = full;
  };

  try {
    send_telemetry(true);
    while (!run.finished()) {
      if (run.stop_requested()) {
        run.end(sim::RunEnd::stopped);
        break;
      }
      // The physics: every step that is due, whatever the planner is doing.
      bool stepped = false;
      while (!run.finished() && Clock::now() >= run.next_step_due()) {
        run.step();
        stepped = true;
      }
      if (run.finished()) break;
      if (!awaiting && stepped) send_telemetry(true);
      const auto reply_deadline = sent_at + options.reply_timeout;
      if (awaiting && Clock::now() >= reply_deadline) {
        throw sim::PlannerFailure("the planner stalled: no reply within " +
                                  seconds_text(options.reply_timeout));
      }

      const auto frame = connection.receive(
          awaiting ? std::min(run.next_step_due(), reply_deadline) : run.next_step_due());
      if (!frame) continue;
      const Sorted s = sort_planner_frame(*frame);
      if (s.kind == Sorted::fatal) throw sim::PlannerFailure(s.text);
      if (s.kind == Sorted::pong) continue;  // unasked: a heartbeat, allowed by RFC 6455
      if (s.kind == Sorted::ignore) {
        log(LogLevel::info, s.text);
        continue;
      }
      if (s.kind == Sorted::ping) {
        connection.send(s.text, Clock::now() + options.reply_timeout);
        continue;
      }
      if (!awaiting) {
        log(LogLevel::warning,
            "the planner replied twice to one telemetry; the extra reply is ignored: " +
                excerpt(frame->text, 40));
        continue;
      }
      auto reply = parse_reply(frame->text, options.limits);
      if (!reply) throw sim::PlannerFailure("malformed reply: " + reply.error());
      awaiting = false;
      std::optional<double> round_trip_us;
      if (awaiting_full) {
        round_trip_us =
            std::chrono::duration<double, std::micro>(Clock::now() - sent_at).count();
      }
      if (!reply.value().manual) {
        run.apply(core::normal_plan(std::move(reply).value().path), round_trip_us,
                  round_trip_us.value_or(0.0));
      } else if (round_trip_us) {
        run.count_cycle(core::normal_plan({}), *round_trip_us, *round_trip_us);
      }
      // Next telemetry: full when anything stepped; null once when nothing did; after the
      // answer to a null one, the next step sends it.
      if (world.steps() > last_full_step) {
        send_telemetry(true);
      } else if (awaiting_full) {
        send_telemetry(false);
      }
    }
  } catch (const ConnectionError& e) {
    run.end(sim::RunEnd::planner_failed, e.what());
  } catch (const sim::PlannerFailure& e) {
    run.end(sim::RunEnd::planner_failed, e.what());
  }
  return run.report();
}

}  // namespace overtake::protocol
