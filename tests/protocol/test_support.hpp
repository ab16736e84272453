#pragma once
// Helpers for the protocol tests: our server in a background thread, a fake planner server
// with scripted behaviour, and a raw TCP client for frames no websocket library would send.
// Everything is loopback (127.0.0.1) and every wait has a deadline.

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

// GCC 12 with the sanitizers reports a false maybe-uninitialized inside Beast's HTTP parser
// (boost::optional); the library's own headers are otherwise warning-free.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/asio/co_spawn.hpp>
#include <boost/asio/connect.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/read_until.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/this_coro.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#pragma GCC diagnostic pop

#include "overtake/protocol/client.hpp"
#include "overtake/protocol/server.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"

namespace overtake::protocol::testing {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;
using namespace std::chrono_literals;

/// The built-in track, loaded once.
inline std::shared_ptr<const run::Track> default_track() {
  static const auto track = run::load_track(std::nullopt);
  return track;
}

/// Collects log lines from several threads.
class LogCapture {
 public:
  LogFn sink() {
    return [this](LogLevel level, std::string_view line) {
      const std::lock_guard lock(mutex_);
      lines_.push_back({level, std::string(line)});
    };
  }
  [[nodiscard]] std::vector<std::string> lines(std::optional<LogLevel> level = std::nullopt) const {
    const std::lock_guard lock(mutex_);
    std::vector<std::string> out;
    for (const auto& [l, text] : lines_) {
      if (!level || l == *level) out.push_back(text);
    }
    return out;
  }
  [[nodiscard]] std::size_t warnings() const { return lines(LogLevel::warning).size(); }
  [[nodiscard]] std::string dump() const {
    std::string out;
    for (const auto& l : lines()) out += "  " + l + "\n";
    return out;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<std::pair<LogLevel, std::string>> lines_;
};

/// `overtake serve` in a background thread on a free port; stopped when destroyed.
class ServerFixture {
 public:
  explicit ServerFixture(std::string policy = "walkthrough",
                         const std::function<void(ServeOptions&)>& adjust = {}) {
    const auto track = default_track();
    PlannerSetup setup;
    setup.line = std::shared_ptr<const core::ReferenceLine>(track, &track->line);
    setup.params = run::default_config().planner;
    setup.policy = std::move(policy);
    ServeOptions opts;
    opts.port = 0;
    opts.status_lines = false;
    opts.handshake_timeout = 2s;
    opts.log = log_.sink();
    if (adjust) adjust(opts);
    std::promise<std::uint16_t> bound;
    auto bound_future = bound.get_future();
    thread_ = std::thread([this, setup, opts, p = std::move(bound)]() mutable {
      try {
        run_server(ioc_, setup, opts, [&p](std::uint16_t port) { p.set_value(port); });
      } catch (...) {
        p.set_exception(std::current_exception());
      }
    });
    if (bound_future.wait_for(10s) != std::future_status::ready) {
      ioc_.stop();
      thread_.join();
      throw std::runtime_error("the server did not start");
    }
    port_ = bound_future.get();
  }
  ~ServerFixture() {
    ioc_.stop();
    thread_.join();
  }
  ServerFixture(const ServerFixture&) = delete;
  ServerFixture& operator=(const ServerFixture&) = delete;

  [[nodiscard]] std::uint16_t port() const { return port_; }
  [[nodiscard]] std::string url() const { return "ws://127.0.0.1:" + std::to_string(port_); }
  [[nodiscard]] PlannerUrl planner_url() const { return parse_planner_url(url()).value(); }
  [[nodiscard]] const LogCapture& log() const { return log_; }

 private:
  LogCapture log_;
  net::io_context ioc_;
  std::thread thread_;
  std::uint16_t port_ = 0;
};

/// Client options for tests: short timeouts, logs captured.
inline ClientOptions quick_client(LogCapture* log = nullptr) {
  ClientOptions o;
  o.connect_timeout = 3s;
  o.reply_timeout = 3s;
  if (log) o.log = log->sink();
  return o;
}

/// A frame a fake planner sends some time after the message it answers.
struct TimedFrame {
  std::chrono::milliseconds after{0};  ///< from the moment the message was read
  std::string frame;
};

/// What a fake planner does with one message it received (`index` counts from 0).
struct FakeAction {
  std::vector<std::string> frames;  ///< sent in order
  bool one_write = false;           ///< all frames in one TCP write (raw, unmasked)
  bool binary = false;              ///< send the frames as binary frames
  bool close = false;               ///< close the websocket afterwards
  bool drop = false;                ///< close the TCP socket abruptly afterwards
  /// After `frames`: wait this long, reading nothing (so a ping that came after the message
  /// is answered only afterwards, as by a planner that sleeps in its message handler), then
  /// send `after_pause`.
  std::chrono::milliseconds pause{0};
  std::vector<std::string> after_pause{};
  /// Sent on timers while the session goes on reading and answering pings (as by a planner
  /// whose answers come from another task or thread).
  std::vector<TimedFrame> later{};
  /// A close frame (code 1000), then, `exit_after` later, the socket closed without waiting
  /// for the client's close frame: a planner that closes normally and exits.
  bool close_then_exit = false;
  std::chrono::milliseconds exit_after{0};
};
using FakeBehaviour = std::function<FakeAction(std::string_view message, int index)>;

// GCC 12 with the sanitizers at -O2 reports a false -Wmismatched-new-delete where a
// coroutine's frame (allocated by Asio's awaitable frame operator new) is freed by its
// matching operator delete; the fake planner's coroutines trigger it.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpragmas"
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
/// A planner server with scripted behaviour, in a background thread; serves one connection
/// at a time. Stopped when destroyed.
class FakePlanner {
 public:
  explicit FakePlanner(FakeBehaviour behaviour, std::uint16_t port = 0)
      : behaviour_(std::move(behaviour)) {
    tcp::acceptor acceptor(ioc_, {net::ip::make_address("127.0.0.1"), port});
    port_ = acceptor.local_endpoint().port();
    net::co_spawn(ioc_, serve(std::move(acceptor)), net::detached);
    thread_ = std::thread([this] { ioc_.run(); });
  }
  ~FakePlanner() {
    ioc_.stop();
    thread_.join();
  }
  FakePlanner(const FakePlanner&) = delete;
  FakePlanner& operator=(const FakePlanner&) = delete;

  [[nodiscard]] std::string url() const { return "ws://127.0.0.1:" + std::to_string(port_); }
  [[nodiscard]] std::vector<std::string> received() const {
    const std::lock_guard lock(mutex_);
    return received_;
  }
  [[nodiscard]] std::string upgrade_request() const {
    const std::lock_guard lock(mutex_);
    return upgrade_request_;
  }

  /// A server frame (unmasked text) as bytes.
  static std::string raw_text_frame(std::string_view payload) {
    std::string f;
    f += static_cast<char>(0x81);
    if (payload.size() < 126) {
      f += static_cast<char>(payload.size());
    } else {
      f += static_cast<char>(126);
      f += static_cast<char>((payload.size() >> 8) & 0xff);
      f += static_cast<char>(payload.size() & 0xff);
    }
    f += payload;
    return f;
  }

 private:
  net::awaitable<void> serve(tcp::acceptor acceptor) {
    for (;;) {
      beast::error_code ec;
      tcp::socket socket =
          co_await acceptor.async_accept(net::redirect_error(net::use_awaitable, ec));
      if (ec) co_return;
      co_await session(std::move(socket));
    }
  }

  // One websocket write at a time: the session and its timed frames share the stream.
  struct Writer {
    websocket::stream<tcp::socket> ws;
    bool busy = false;
    explicit Writer(tcp::socket s) : ws(std::move(s)) {}
  };

  static net::awaitable<void> write_frame(std::shared_ptr<Writer> w, std::string text, bool binary,
                                          beast::error_code& ec) {
    net::steady_timer wait(co_await net::this_coro::executor);
    while (w->busy) {
      wait.expires_after(1ms);
      co_await wait.async_wait(net::redirect_error(net::use_awaitable, ec));
    }
    w->busy = true;
    w->ws.binary(binary);
    co_await w->ws.async_write(net::buffer(text), net::redirect_error(net::use_awaitable, ec));
    w->busy = false;
  }

  static net::awaitable<void> send_later(std::shared_ptr<Writer> w, TimedFrame f) {
    net::steady_timer timer(co_await net::this_coro::executor);
    beast::error_code ec;
    timer.expires_after(f.after);
    co_await timer.async_wait(net::redirect_error(net::use_awaitable, ec));
    if (!w->ws.is_open()) co_return;
    co_await write_frame(w, std::move(f.frame), false, ec);
  }

  net::awaitable<void> session(tcp::socket socket) {
    beast::error_code ec;
    auto w = std::make_shared<Writer>(std::move(socket));
    websocket::stream<tcp::socket>& ws = w->ws;
    // The request as it came, for the tests to read; the upgrade is then done from it. (A
    // client speaks only after the 101, so nothing follows the request yet.)
    std::string request;
    co_await net::async_read_until(ws.next_layer(), net::dynamic_buffer(request), "\r\n\r\n",
                                   net::redirect_error(net::use_awaitable, ec));
    if (ec) co_return;
    {
      const std::lock_guard lock(mutex_);
      upgrade_request_ = request;
    }
    co_await ws.async_accept(net::buffer(request), net::redirect_error(net::use_awaitable, ec));
    if (ec) co_return;
    beast::flat_buffer buffer;
    for (int index = 0;; ++index) {
      buffer.clear();
      co_await ws.async_read(buffer, net::redirect_error(net::use_awaitable, ec));
      if (ec) co_return;
      const std::string message = beast::buffers_to_string(buffer.data());
      {
        const std::lock_guard lock(mutex_);
        received_.push_back(message);
      }
      const FakeAction action = behaviour_(message, index);
      for (const TimedFrame& f : action.later) {
        net::co_spawn(co_await net::this_coro::executor, send_later(w, f), net::detached);
      }
      if (action.one_write) {
        std::string bytes;
        for (const auto& f : action.frames) bytes += raw_text_frame(f);
        co_await net::async_write(ws.next_layer(), net::buffer(bytes),
                                  net::redirect_error(net::use_awaitable, ec));
      } else {
        for (const auto& f : action.frames) {
          co_await write_frame(w, f, action.binary, ec);
          if (ec) co_return;
        }
      }
      if (ec) co_return;
      if (action.pause > 0ms) {
        net::steady_timer pause(co_await net::this_coro::executor);
        pause.expires_after(action.pause);
        co_await pause.async_wait(net::redirect_error(net::use_awaitable, ec));
        for (const auto& f : action.after_pause) {
          co_await write_frame(w, f, false, ec);
          if (ec) co_return;
        }
      }
      if (action.close_then_exit) {
        // Sent at once (Nagle's algorithm off): a frame still held back for an acknowledgement
        // when the socket is closed is thrown away with the reset that closing then sends
        // (when our ping is still unread), and the client would rightly see only the reset.
        ws.next_layer().set_option(tcp::no_delay(true), ec);
        const std::string close_frame("\x88\x02\x03\xe8", 4);  // close, code 1000
        co_await net::async_write(ws.next_layer(), net::buffer(close_frame),
                                  net::redirect_error(net::use_awaitable, ec));
        net::steady_timer pause(co_await net::this_coro::executor);
        pause.expires_after(action.exit_after);
        co_await pause.async_wait(net::redirect_error(net::use_awaitable, ec));
        ws.next_layer().close(ec);
        co_return;
      }
      if (action.close) {
        co_await ws.async_close(websocket::close_code::normal,
                                net::redirect_error(net::use_awaitable, ec));
        co_return;
      }
      if (action.drop) {
        ws.next_layer().close(ec);
        co_return;
      }
    }
  }

  FakeBehaviour behaviour_;
  net::io_context ioc_;
  std::thread thread_;
  std::uint16_t port_ = 0;
  mutable std::mutex mutex_;
  std::vector<std::string> received_;
  std::string upgrade_request_;
};
#pragma GCC diagnostic pop

/// A TCP client that writes whatever bytes a test wants, with deadlines on every read.
class RawClient {
 public:
  explicit RawClient(std::uint16_t port) : socket_(ioc_) {
    socket_.connect({net::ip::make_address("127.0.0.1"), port});
    socket_.set_option(tcp::no_delay(true));
    local_port_ = socket_.local_endpoint().port();
  }
  /// The client's own port, which the server's log lines name.
  [[nodiscard]] std::uint16_t local_port() const { return local_port_; }
  void write(std::string_view bytes) {
    beast::error_code ec;
    net::write(socket_, net::buffer(bytes), ec);
  }
  /// Sends a websocket upgrade request; returns the response head ("" when none came).
  std::string upgrade(const std::string& extra_headers = {}) {
    write(
        "GET /socket.io/?EIO=4&transport=websocket HTTP/1.1\r\nHost: 127.0.0.1\r\n"
        "Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: "
        "dGhlIHNhbXBsZSBub25jZQ==\r\n"
        "Sec-WebSocket-Version: 13\r\n" +
        extra_headers + "\r\n");
    return read_until("\r\n\r\n", 3s);
  }
  /// A client frame (masked with a zero key, so the payload reads as is).
  static std::string frame(std::uint8_t first_byte, std::string_view payload, bool masked = true) {
    std::string f;
    f += static_cast<char>(first_byte);
    const char mask_bit = masked ? static_cast<char>(0x80) : 0;
    if (payload.size() < 126) {
      f += static_cast<char>(mask_bit | static_cast<char>(payload.size()));
    } else if (payload.size() < 65536) {
      f += static_cast<char>(mask_bit | 126);
      f += static_cast<char>((payload.size() >> 8) & 0xff);
      f += static_cast<char>(payload.size() & 0xff);
    } else {
      f += static_cast<char>(mask_bit | 127);
      for (int shift = 56; shift >= 0; shift -= 8)
        f += static_cast<char>((payload.size() >> shift) & 0xff);
    }
    if (masked) f += std::string(4, '\0');
    f += payload;
    return f;
  }
  /// Reads until `delim` or the deadline; returns what came (up to and including delim).
  std::string read_until(std::string_view delim, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (pending_.find(delim) == std::string::npos && read_some(deadline)) {
    }
    const auto at = pending_.find(delim);
    if (at == std::string::npos) return std::exchange(pending_, {});
    std::string out = pending_.substr(0, at + delim.size());
    pending_.erase(0, at + delim.size());
    return out;
  }
  /// True when the server closed the connection (EOF or reset) before the deadline. Any data
  /// that came first (e.g. a close frame) is in `seen`.
  bool closed_by_peer(std::chrono::milliseconds timeout, std::string* seen = nullptr) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (read_some(deadline)) {
    }
    if (seen) *seen = pending_;
    return eof_;
  }
  /// Reads the next server frame's payload (unmasked frames), or nullopt by the deadline.
  std::optional<std::string> read_frame(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      if (pending_.size() >= 2) {
        std::size_t len = static_cast<unsigned char>(pending_[1]) & 0x7f;
        std::size_t head = 2;
        if (len == 126 && pending_.size() >= 4) {
          len = (static_cast<unsigned char>(pending_[2]) << 8) |
                static_cast<unsigned char>(pending_[3]);
          head = 4;
        }
        if (len != 126 && len != 127 && pending_.size() >= head + len) {
          std::string payload = pending_.substr(head, len);
          pending_.erase(0, head + len);
          return payload;
        }
      }
      if (!read_some(deadline)) return std::nullopt;
    }
  }
  void close_gracefully() {
    beast::error_code ec;
    socket_.shutdown(tcp::socket::shutdown_both, ec);
    socket_.close(ec);
  }
  void close_abruptly() {
    beast::error_code ec;
    socket_.set_option(net::socket_base::linger(true, 0), ec);  // RST instead of FIN
    socket_.close(ec);
  }

 private:
  bool read_some(std::chrono::steady_clock::time_point deadline) {
    if (eof_) return false;
    char buf[4096];
    bool done = false;
    bool got = false;
    socket_.async_read_some(net::buffer(buf), [&](const beast::error_code& ec, std::size_t n) {
      done = true;
      if (ec) {
        if (ec != net::error::operation_aborted) eof_ = true;
        return;
      }
      pending_.append(buf, n);
      got = true;
    });
    ioc_.restart();
    ioc_.run_until(deadline);
    if (!done) {
      beast::error_code ec;
      socket_.cancel(ec);
      ioc_.restart();
      ioc_.run();
    }
    return got;
  }

  net::io_context ioc_;
  tcp::socket socket_;
  std::string pending_;
  bool eof_ = false;
  std::uint16_t local_port_ = 0;
};

/// A telemetry exactly as the original simulator printed it at the start of its map.
inline constexpr std::string_view kRecordedTelemetry =
    R"(42["telemetry",{"x":909.48,"y":1128.67,"yaw":0,"speed":0,"s":124.8336,"d":6.164833,)"
    R"("previous_path_x":[],"previous_path_y":[],"end_path_s":0,"end_path_d":0,)"
    R"("sensor_fusion":[[0,775.99,1132.11,22.1,-0.3651,85.3,2.012]]}])";

/// The first telemetry of a world on the default track (seed 1), as our client sends it.
inline std::string start_telemetry() {
  const auto track = default_track();
  const sim::World world(track->map, track->line, run::default_config().world,
                         sim::TrafficProfile::faithful, 1);
  return format_telemetry(world.telemetry());
}

}  // namespace overtake::protocol::testing
