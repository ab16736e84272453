// The simulator's websocket client: the planner's address, and a connection with deadlines on
// everything (connect, send, receive, close).

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <deque>
#include <thread>

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

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

#include "overtake/protocol/client.hpp"

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
    if (opts.open_socket) {
      // A socket made elsewhere (a planner program's network namespace): connected as it is,
      // to the first address (connecting to a range would make sockets of our own).
      const tcp::endpoint to = *endpoints.begin();
      const int fd = opts.open_socket();
      if (fd < 0) return "cannot make a socket in the planner's network";
      ws->next_layer().assign(to.protocol(), fd, ec);
      if (ec) {
        ::close(fd);
        return "cannot use the planner network's socket (" + ec.message() + ")";
      }
      ws->next_layer().async_connect(to, [&](const error_code& e) {
        ec = e;
        done = true;
      });
    } else {
      net::async_connect(ws->next_layer(), endpoints,
                         [&](const error_code& e, const tcp::endpoint&) {
                           ec = e;
                           done = true;
                         });
    }
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
  const auto stopped = [&options] {
    return options.stop != nullptr && options.stop->load(std::memory_order_relaxed);
  };
  for (;;) {
    // Ctrl-C while a planner is still starting stops the wait (within one retry delay, or one
    // attempt when a peer accepts but never completes the upgrade).
    if (stopped()) throw ConnectionError("stopped before the planner listened");
    const auto attempt_deadline = std::min(deadline, Clock::now() + kAttemptTimeout);
    const std::string why = impl_->attempt(url, attempt_deadline);
    if (why.empty()) return;
    if (options.give_up) {
      const std::string reason = options.give_up();
      if (!reason.empty()) {
        throw ConnectionError("cannot connect to the planner at " + to_string(url) + ": " + reason);
      }
    }
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

}  // namespace overtake::protocol
