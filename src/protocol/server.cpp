// `overtake serve`: accept loop, one coroutine per connection, a status line a second.

#include "overtake/protocol/server.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <thread>
#include <utility>
#include <vector>

// GCC 12 may report a false maybe-uninitialized inside Beast's HTTP parser (boost::optional)
// depending on inlining (seen with the sanitizers).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/asio/co_spawn.hpp>
#include <boost/asio/detached.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/redirect_error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/this_coro.hpp>
#include <boost/asio/use_awaitable.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#pragma GCC diagnostic pop

#include "overtake/core/road.hpp"
#include "overtake/core/units.hpp"
#include "overtake/planner/policy.hpp"

namespace overtake::protocol {
namespace {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;
using beast::error_code;

constexpr std::size_t kReadChunk = 64 * 1024;
constexpr std::size_t kOversizedHeadBytes = 64;  // kept of a dropped frame, for its log line
constexpr auto kStatusPeriod = std::chrono::seconds(1);
constexpr auto kAcceptRetryDelay = std::chrono::milliseconds(100);

std::string endpoint_text(const tcp::endpoint& ep) {
  const auto addr = ep.address();
  return (addr.is_v6() ? "[" + addr.to_string() + "]" : addr.to_string()) + ":" +
         std::to_string(ep.port());
}

// Everything the server keeps, shared by the accept loop, the sessions and the status line.
// One thread runs the io_context, so nothing here needs a lock.
struct ServerState {
  PlannerSetup setup;
  ServeOptions opts;
  int next_id = 1;
  int open = 0;
  long cycles_total = 0;
  long cycles_window = 0;
  std::vector<double> plan_us_window;
  std::optional<core::EgoObservation> last_ego;

  void log(LogLevel level, const std::string& line) const { opts.log(level, line); }
};

// Keeps the count of open connections right however a session ends.
class OpenCount {
 public:
  explicit OpenCount(ServerState& st) : st_(st) { ++st_.open; }
  ~OpenCount() { --st_.open; }
  OpenCount(const OpenCount&) = delete;
  OpenCount& operator=(const OpenCount&) = delete;

 private:
  ServerState& st_;
};

std::string cycles_text(long n) {
  return std::to_string(n) + (n == 1 ? " cycle" : " cycles");
}

// The log line for a connection that ended with `ec` (empty when the server is stopping).
// `peer_close`: the peer's close frame, when one came (code `none` otherwise).
std::optional<std::pair<LogLevel, std::string>> end_line(
    const error_code& ec, const websocket::close_reason& peer_close) {
  if (ec == net::error::operation_aborted) return std::nullopt;
  // After the peer's close frame, tearing the connection down may fail (a peer that goes
  // without waiting for our close frame: "Transport endpoint is not connected"); the peer
  // closed all the same.
  if (peer_close.code != websocket::close_code::none) {
    return std::pair{LogLevel::info, "closed by the peer (close code " +
                                         std::to_string(static_cast<unsigned>(peer_close.code)) +
                                         ")"};
  }
  if (ec == websocket::error::closed)
    return std::pair{LogLevel::info, std::string("closed by the peer")};
  if (ec == net::error::eof || ec == net::error::connection_reset ||
      ec == net::error::broken_pipe || ec == beast::error::timeout) {
    return std::pair{LogLevel::info, "dropped (" + ec.message() + ")"};
  }
  // Websocket protocol violations: Beast has failed the connection with a close frame.
  return std::pair{LogLevel::warning,
                   "closed after a websocket protocol error (" + ec.message() + ")"};
}

using WsStream = websocket::stream<beast::tcp_stream>;

// The websocket upgrade: true when the connection is open. One from a browser page (an Origin
// header) is refused with a 403 and closed.
net::awaitable<bool> upgrade(WsStream& ws, ServerState* st, const std::string& who) {
  error_code ec;
  // The upgrade request is read here, not by the accept, to look at its Origin first. (A
  // client speaks only after the 101, so nothing after the request is left in the buffer.)
  beast::flat_buffer request_buffer;
  http::request<http::empty_body> request;
  beast::get_lowest_layer(ws).expires_after(st->opts.handshake_timeout);
  co_await http::async_read(ws.next_layer(), request_buffer, request,
                            net::redirect_error(net::use_awaitable, ec));
  beast::get_lowest_layer(ws).expires_never();  // the websocket's own timeouts from here on
  if (!ec) {
    if (const auto origin = request.find(http::field::origin); origin != request.end()) {
      // Browsers send an Origin with every websocket upgrade, the simulator and planner
      // programs none. `serve` serves no page, so any page that opens a websocket here is
      // another site's (or a DNS-rebinding one's): it would drive a planner of this machine.
      const std::string_view value(origin->value().data(), origin->value().size());
      st->log(LogLevel::warning,
              who + ": websocket upgrade refused: it comes from a browser page (Origin: " +
                  excerpt(value) + "), closed");
      http::response<http::string_body> res{http::status::forbidden, request.version()};
      res.set(http::field::server, "overtake");
      res.set(http::field::content_type, "text/plain; charset=utf-8");
      res.keep_alive(false);
      res.body() =
          "websocket refused: the request has an Origin header, so it comes from a web page; "
          "this planner server answers the simulator and planner programs only, which send "
          "none\n";
      res.prepare_payload();
      beast::get_lowest_layer(ws).expires_after(st->opts.handshake_timeout);
      co_await http::async_write(ws.next_layer(), res, net::redirect_error(net::use_awaitable, ec));
      beast::get_lowest_layer(ws).socket().shutdown(tcp::socket::shutdown_both, ec);
      co_return false;
    }
    co_await ws.async_accept(request, net::redirect_error(net::use_awaitable, ec));  // any path
  }
  if (ec) {
    if (ec != net::error::operation_aborted) {
      st->log(LogLevel::warning, who + ": no websocket upgrade (" + ec.message() + "), closed");
    }
    co_return false;
  }
  co_return true;
}

// The connection's planner session, frame after frame, until the client leaves or fails.
net::awaitable<void> session_loop(WsStream& ws, ServerState* st, const std::string& who) {
  error_code ec;
  const OpenCount counted(*st);
  PlannerSession session(st->setup.factory(*st->setup.line, st->setup.params), st->opts.limits,
                         st->opts.max_frame_bytes);
  long cycles = 0;
  beast::flat_buffer buffer;
  std::string head;
  for (;;) {
    buffer.clear();
    std::size_t size = 0;
    bool oversized = false;
    do {
      const std::size_t n = co_await ws.async_read_some(
          buffer, kReadChunk, net::redirect_error(net::use_awaitable, ec));
      if (ec) {
        if (const auto line = end_line(ec, ws.reason())) {
          st->log(line->first, who + " " + line->second + " after " + cycles_text(cycles));
        }
        co_return;
      }
      size += n;
      if (!oversized && buffer.size() > st->opts.max_frame_bytes) {
        oversized = true;
        const auto data = buffer.data();
        head.assign(static_cast<const char*>(data.data()),
                    std::min(data.size(), kOversizedHeadBytes));
      }
      if (oversized) buffer.clear();  // keep reading the message, keep none of it
    } while (!ws.is_message_done());

    Frame frame;
    frame.binary = ws.got_binary();
    frame.oversized = oversized;
    frame.size = size;
    frame.text =
        oversized ? std::string_view(head)
                  : std::string_view(static_cast<const char*>(buffer.data().data()), buffer.size());
    const FrameOutcome out = session.handle(frame);
    if (out.warning) st->log(LogLevel::warning, who + ": " + *out.warning);
    if (out.note) st->log(LogLevel::info, who + ": " + *out.note);
    if (out.planned) {
      ++cycles;
      ++st->cycles_total;
      ++st->cycles_window;
      st->plan_us_window.push_back(out.plan_us);
    }
    if (out.ego) st->last_ego = out.ego;
    if (!out.reply) continue;
    ws.text(true);
    co_await ws.async_write(net::buffer(*out.reply), net::redirect_error(net::use_awaitable, ec));
    if (ec) {
      if (const auto line = end_line(ec, ws.reason())) {
        st->log(line->first, who + " " + line->second + " after " + cycles_text(cycles));
      }
      co_return;
    }
  }
}

net::awaitable<void> serve_connection(tcp::socket socket, std::shared_ptr<ServerState> st) {
  const int id = st->next_id++;
  error_code ec;
  const auto remote = socket.remote_endpoint(ec);
  const std::string who =
      "connection #" + std::to_string(id) + " (" + (ec ? "?" : endpoint_text(remote)) + ")";
  socket.set_option(tcp::no_delay(true), ec);  // small frames, one at a time: no Nagle delay

  try {
    WsStream ws(std::move(socket));
    ws.set_option(websocket::permessage_deflate{});  // the original rejects any extension
    websocket::stream_base::timeout timeouts{};
    timeouts.handshake_timeout = st->opts.handshake_timeout;
    timeouts.idle_timeout = websocket::stream_base::none();
    timeouts.keep_alive_pings = false;
    ws.set_option(timeouts);
    ws.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& res) { res.set(beast::http::field::server, "overtake"); }));
    ws.read_message_max(0);  // sizes are limited below, without failing the connection

    if (!co_await upgrade(ws, st.get(), who)) co_return;
    st->log(LogLevel::info, who + " open");
    co_await session_loop(ws, st.get(), who);
  } catch (const std::exception& e) {  // nothing may escape: a session ends, the server stays
    st->log(LogLevel::warning, who + ": internal error (" + e.what() + "), connection closed");
  }
}

net::awaitable<void> accept_loop(tcp::acceptor acceptor, std::shared_ptr<ServerState> st) {
  net::steady_timer pause(acceptor.get_executor());
  for (;;) {
    error_code ec;
    tcp::socket socket =
        co_await acceptor.async_accept(net::redirect_error(net::use_awaitable, ec));
    if (ec == net::error::operation_aborted) co_return;
    if (ec) {  // e.g. out of file descriptors: say so, wait a little, go on
      st->log(LogLevel::warning, "cannot accept a connection (" + ec.message() + ")");
      pause.expires_after(kAcceptRetryDelay);
      co_await pause.async_wait(net::redirect_error(net::use_awaitable, ec));
      continue;
    }
    net::co_spawn(acceptor.get_executor(), serve_connection(std::move(socket), st), net::detached);
  }
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

net::awaitable<void> status_loop(std::shared_ptr<ServerState> st) {
  net::steady_timer timer(co_await net::this_coro::executor);
  for (;;) {
    error_code ec;
    timer.expires_after(kStatusPeriod);
    co_await timer.async_wait(net::redirect_error(net::use_awaitable, ec));
    if (ec) co_return;
    if (st->open > 0) {
      char line[256];
      const double max_us =
          st->plan_us_window.empty()
              ? 0.0
              : *std::max_element(st->plan_us_window.begin(), st->plan_us_window.end());
      const auto& ego = st->last_ego;
      std::snprintf(
          line, sizeof line,
          "status: %d connection%s, %ld cycles/s (%ld in all), %.1f mph, lane %d, planner "
          "median %.0f us, max %.0f us",
          st->open, st->open == 1 ? "" : "s", st->cycles_window, st->cycles_total,
          ego ? core::mps_to_mph(ego->speed_mps) : 0.0,
          ego ? core::lane_of(ego->d_m, st->setup.params.road) : -1, median(st->plan_us_window),
          max_us);
      st->log(LogLevel::info, line);
    }
    st->cycles_window = 0;
    st->plan_us_window.clear();
  }
}

tcp::endpoint listen_endpoint(net::io_context& ioc, const ServeOptions& opts) {
  error_code ec;
  const auto addr = net::ip::make_address(opts.host, ec);
  if (!ec) return {addr, opts.port};
  tcp::resolver resolver(ioc);
  const auto results = resolver.resolve(opts.host, std::to_string(opts.port), ec);
  if (ec || results.empty()) {
    throw std::runtime_error("--host: cannot resolve '" + opts.host + "' (" + ec.message() + ")");
  }
  return results.begin()->endpoint();
}

}  // namespace

void run_server(net::io_context& ioc, const PlannerSetup& setup, const ServeOptions& opts,
                const std::function<void(std::uint16_t)>& on_listening) {
  if (!setup.line) throw std::invalid_argument("run_server: no reference line");
  planner::PolicyFactory factory =
      setup.factory ? setup.factory : planner::builtin_policy_factory(setup.policy);
  if (!factory) {
    throw std::invalid_argument("--policy: " + planner::unknown_policy_text(setup.policy));
  }
  if (opts.max_frame_bytes == 0)
    throw std::invalid_argument("--max-frame-bytes must be at least 1");

  auto st = std::make_shared<ServerState>();
  st->setup = setup;
  st->setup.factory = std::move(factory);
  st->opts = opts;
  if (!st->opts.log) st->opts.log = stderr_log(true);

  const tcp::endpoint ep = listen_endpoint(ioc, opts);
  tcp::acceptor acceptor(ioc);
  error_code ec;
  acceptor.open(ep.protocol(), ec);
  if (!ec) acceptor.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) acceptor.bind(ep, ec);
  if (!ec) acceptor.listen(net::socket_base::max_listen_connections, ec);
  if (ec)
    throw std::runtime_error("cannot listen on " + endpoint_text(ep) + " (" + ec.message() + ")");
  const tcp::endpoint bound = acceptor.local_endpoint();

  st->log(LogLevel::info,
          "listening on ws://" + endpoint_text(bound) + " with policy " + setup.policy);
  net::co_spawn(ioc, accept_loop(std::move(acceptor), st), net::detached);
  if (opts.status_lines) net::co_spawn(ioc, status_loop(st), net::detached);
  if (on_listening) on_listening(bound.port());
  ioc.run();
}

void serve_until(const PlannerSetup& setup, const ServeOptions& opts, const std::atomic<bool>& stop,
                 const std::function<void()>& on_stop) {
  net::io_context ioc;
  // Stops the server when the flag is set; ends with this function, however it ends.
  struct Stopper {
    std::atomic<bool> served{false};
    std::thread thread;
    Stopper() = default;
    Stopper(const Stopper&) = delete;
    Stopper& operator=(const Stopper&) = delete;
    ~Stopper() {
      served = true;
      if (thread.joinable()) thread.join();
    }
  } stopper;
  stopper.thread = std::thread([&ioc, &stop, &on_stop, &served = stopper.served] {
    while (!served.load()) {
      if (stop.load()) {
        if (on_stop) on_stop();
        ioc.stop();
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  run_server(ioc, setup, opts);
}

}  // namespace overtake::protocol
