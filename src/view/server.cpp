// The view server (HTTP + the live websocket) and the live feed.

#include "overtake/view/server.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <iterator>
#include <optional>
#include <thread>
#include <utility>

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

namespace overtake::view {
namespace {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;
using beast::error_code;
using WsStream = websocket::stream<beast::tcp_stream>;

constexpr auto kHttpTimeout = std::chrono::seconds(30);
constexpr std::size_t kMaxRequestBodyBytes = 64 * 1024;
constexpr auto kLivePoll = std::chrono::milliseconds(20);
constexpr std::size_t kMaxLiveMessageBytes = std::size_t{4} << 20;
constexpr auto kAcceptRetryDelay = std::chrono::milliseconds(100);

std::string_view target_of(const http::request<http::string_body>& req) {
  return {req.target().data(), req.target().size()};
}

struct Shared {
  ViewContent content;
  std::string bound_host;  // as given to listen on, for host_allowed()
};

// ---- who may ask ----------------------------------------------------------------------------

// At most 80 printable characters of a header value, for an error page.
std::string shown(std::string_view value) {
  std::string out;
  for (const char c : value.substr(0, 80)) {
    out += std::isprint(static_cast<unsigned char>(c)) ? c : '?';
  }
  return value.size() > 80 ? out + "..." : out;
}

// The answer to a request this server does not serve to whoever sent it, or nullopt:
// - a Host that does not name this machine (421): a page that reaches the server through
//   DNS rebinding sends its own name, and must read nothing;
// - no Host in HTTP/1.1, or more than one (400);
// - a websocket upgrade whose Origin is not the page served here (403): any site the user
//   visits may open a websocket anywhere; programs (and our tests) send no Origin.
std::optional<http::response<http::string_body>> refusal(
    const http::request<http::string_body>& req, const Shared& sh) {
  const auto refuse = [&req](http::status status, std::string body) {
    http::response<http::string_body> res{status, req.version()};
    res.set(http::field::server, "overtake");
    res.set(http::field::content_type, "text/plain; charset=utf-8");
    res.set(http::field::cache_control, "no-store");
    res.keep_alive(false);
    res.body() = std::move(body);
    res.prepare_payload();
    return res;
  };
  const std::size_t hosts = req.count(http::field::host);
  const std::string_view host(req[http::field::host].data(), req[http::field::host].size());
  if (hosts > 1) return refuse(http::status::bad_request, "more than one Host header\n");
  if (hosts == 0 && req.version() >= 11) {
    return refuse(http::status::bad_request, "the request has no Host header\n");
  }
  if (hosts == 1 && !host_allowed(host, sh.bound_host)) {
    std::string names = "localhost, 127.0.0.1, [::1]";
    const std::string bound = host_for_url(sh.bound_host);
    if (!is_loopback_name(bound)) names += " and " + bound;
    return refuse(http::status::misdirected_request, "this server answers only to " + names +
                                                         " (any port); the request is for '" +
                                                         shown(host) + "'\n");
  }
  if (websocket::is_upgrade(req)) {
    const auto origin = req.find(http::field::origin);
    if (origin != req.end()) {
      const std::string_view value(origin->value().data(), origin->value().size());
      if (!same_origin(value, host)) {
        return refuse(http::status::forbidden, "websocket refused: its Origin '" + shown(value) +
                                                   "' is not the page served here (http://" +
                                                   shown(host) + "); only that page may open it\n");
      }
    }
  }
  return std::nullopt;
}

http::response<http::string_body> respond(const http::request<http::string_body>& req,
                                          const Shared& sh) {
  http::response<http::string_body> res;
  res.version(req.version());
  res.keep_alive(req.keep_alive());
  res.set(http::field::server, "overtake");
  res.set(http::field::cache_control, "no-store");
  res.set("X-Content-Type-Options", "nosniff");
  const bool head = req.method() == http::verb::head;
  if (req.method() != http::verb::get && !head) {
    res.result(http::status::method_not_allowed);
    res.set(http::field::allow, "GET, HEAD");
    res.set(http::field::content_type, "text/plain; charset=utf-8");
    res.body() = "method not allowed\n";
    res.prepare_payload();
    return res;
  }
  const ViewRoute route = route_target(target_of(req), sh.content);
  const std::string* body = nullptr;
  if (route.resource == ViewResource::page) {
    res.set(http::field::content_type, "text/html; charset=utf-8");
    body = &sh.content.page;
  } else if (route.resource == ViewResource::replay) {
    res.set(http::field::content_type, "application/octet-stream");
    body = sh.content.replay.get();
  }
  if (!body) {
    res.result(http::status::not_found);
    res.set(http::field::content_type, "text/plain; charset=utf-8");
    res.body() = "not found: " + std::string(route.path) + "\n";
    res.prepare_payload();
    return res;
  }
  res.result(http::status::ok);
  if (head) {
    res.content_length(body->size());
  } else {
    res.body() = *body;
    res.prepare_payload();
  }
  return res;
}

// Reads (and drops) what the browser sends, so that pings and its close are answered; sets
// `gone` when the connection ends.
net::awaitable<void> drain(std::shared_ptr<WsStream> ws, std::shared_ptr<bool> gone) {
  beast::flat_buffer buffer;
  error_code ec;
  for (;;) {
    co_await ws->async_read(buffer, net::redirect_error(net::use_awaitable, ec));
    if (ec) break;
    buffer.clear();
  }
  *gone = true;
}

net::awaitable<void> live_session(std::shared_ptr<WsStream> ws,
                                  http::request<http::string_body> req,
                                  std::shared_ptr<const LiveFeed> feed) {
  error_code ec;
  ws->set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
  ws->set_option(websocket::stream_base::decorator(
      [](websocket::response_type& res) { res.set(http::field::server, "overtake"); }));
  co_await ws->async_accept(req, net::redirect_error(net::use_awaitable, ec));
  if (ec) co_return;
  auto gone = std::make_shared<bool>(false);
  net::co_spawn(co_await net::this_coro::executor, drain(ws, gone), net::detached);

  ws->text(true);
  co_await ws->async_write(net::buffer(feed->header_json()),
                           net::redirect_error(net::use_awaitable, ec));
  ws->binary(true);
  net::steady_timer timer(co_await net::this_coro::executor);
  std::size_t sent = 0;
  while (!ec && !*gone) {
    LiveFeed::Next next = feed->next(sent);
    if (next.chunks.empty()) {
      if (next.closed) {
        co_await ws->async_close(websocket::close_code::normal,
                                 net::redirect_error(net::use_awaitable, ec));
        co_return;
      }
      timer.expires_after(kLivePoll);
      co_await timer.async_wait(net::redirect_error(net::use_awaitable, ec));
      continue;
    }
    // Whole chunks (whole records) per message, a few megabytes at most.
    std::size_t i = 0;
    while (i < next.chunks.size() && !ec) {
      std::vector<net::const_buffer> message;
      std::size_t bytes = 0;
      for (; i < next.chunks.size(); ++i) {
        const std::string& c = *next.chunks[i];
        if (!message.empty() && bytes + c.size() > kMaxLiveMessageBytes) break;
        message.emplace_back(c.data(), c.size());
        bytes += c.size();
      }
      co_await ws->async_write(message, net::redirect_error(net::use_awaitable, ec));
    }
    sent += next.chunks.size();
  }
  beast::get_lowest_layer(*ws).close();
}

net::awaitable<void> http_session(tcp::socket socket, std::shared_ptr<const Shared> sh) {
  beast::tcp_stream stream(std::move(socket));
  beast::flat_buffer buffer;
  error_code ec;
  try {
    for (;;) {
      stream.expires_after(kHttpTimeout);
      http::request_parser<http::string_body> parser;
      parser.body_limit(kMaxRequestBodyBytes);
      co_await http::async_read(stream, buffer, parser,
                                net::redirect_error(net::use_awaitable, ec));
      if (ec) break;
      http::request<http::string_body> req = parser.release();
      if (auto refused = refusal(req, *sh)) {
        co_await http::async_write(stream, *refused, net::redirect_error(net::use_awaitable, ec));
        break;
      }
      if (websocket::is_upgrade(req) &&
          route_target(target_of(req), sh->content).resource == ViewResource::live) {
        stream.expires_never();
        auto ws = std::make_shared<WsStream>(std::move(stream));
        co_await live_session(ws, std::move(req), sh->content.live);
        co_return;
      }
      http::response<http::string_body> res = respond(req, *sh);
      const bool keep = res.keep_alive();
      co_await http::async_write(stream, res, net::redirect_error(net::use_awaitable, ec));
      if (ec || !keep) break;
    }
    stream.socket().shutdown(tcp::socket::shutdown_send, ec);
  } catch (const std::exception&) {  // a connection's failure ends that connection only
  }
}

net::awaitable<void> accept_loop(tcp::acceptor& acceptor, std::shared_ptr<const Shared> sh) {
  const auto executor = co_await net::this_coro::executor;
  net::steady_timer retry(executor);
  for (;;) {
    error_code ec;
    tcp::socket socket =
        co_await acceptor.async_accept(net::redirect_error(net::use_awaitable, ec));
    if (ec == net::error::operation_aborted || !acceptor.is_open()) co_return;
    if (ec) {  // e.g. out of file descriptors: wait a little and go on
      retry.expires_after(kAcceptRetryDelay);
      co_await retry.async_wait(net::redirect_error(net::use_awaitable, ec));
      continue;
    }
    net::co_spawn(executor, http_session(std::move(socket), sh), net::detached);
  }
}

}  // namespace

// ---- server -------------------------------------------------------------------------------

struct ViewServer::Impl {
  net::io_context ioc{1};  // first: destroyed last, after the handlers that refer to it
  tcp::acceptor acceptor{ioc};
  std::string host;
  std::uint16_t port = 0;
  std::thread thread;
  bool stopped = false;
};

ViewServer::ViewServer(ViewContent content, const ViewServerOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.host = options.host;
  const std::string where = host_for_url(options.host) + ":" + std::to_string(options.port);
  error_code ec;
  tcp::resolver resolver(m.ioc);
  const auto endpoints =
      resolver.resolve(options.host, std::to_string(options.port),
                       tcp::resolver::passive | tcp::resolver::numeric_service, ec);
  if (ec || endpoints.empty()) {
    throw ViewError("cannot listen on " + where + ": the address '" + options.host +
                    "' does not resolve (" + ec.message() + ")");
  }
  const tcp::endpoint endpoint = endpoints.begin()->endpoint();
  m.acceptor.open(endpoint.protocol(), ec);
  if (!ec) m.acceptor.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) m.acceptor.bind(endpoint, ec);
  if (ec == net::error::address_in_use) {
    throw ViewError("cannot listen on " + where +
                    ": the port is already in use (another `overtake view`?); choose another "
                    "with --port, or --port 0 for any free port");
  }
  if (ec == net::error::access_denied) {
    throw ViewError("cannot listen on " + where +
                    ": permission denied (ports below 1024 need privileges); choose another "
                    "with --port");
  }
  if (ec == boost::system::errc::address_not_available) {
    throw ViewError("cannot listen on " + where + ": '" + options.host +
                    "' is not an address of this machine");
  }
  if (!ec) m.acceptor.listen(net::socket_base::max_listen_connections, ec);
  if (ec) throw ViewError("cannot listen on " + where + ": " + ec.message());
  m.port = m.acceptor.local_endpoint().port();

  auto shared = std::make_shared<const Shared>(Shared{std::move(content), options.host});
  net::co_spawn(m.ioc, accept_loop(m.acceptor, std::move(shared)), net::detached);
  m.thread = std::thread([&m] {
    for (;;) {
      try {
        m.ioc.run();
        return;
      } catch (const std::exception&) {  // a handler's failure must not end the server
      }
    }
  });
}

ViewServer::~ViewServer() {
  stop();
}

std::uint16_t ViewServer::port() const {
  return impl_->port;
}

std::string ViewServer::url() const {
  return "http://" + host_for_url(impl_->host) + ":" + std::to_string(impl_->port) + "/";
}

void ViewServer::stop() {
  Impl& m = *impl_;
  if (m.stopped) return;
  m.stopped = true;
  m.ioc.stop();
  if (m.thread.joinable()) m.thread.join();
  error_code ignored;
  m.acceptor.close(ignored);
}

// ---- live view ----------------------------------------------------------------------------

LiveView::LiveView(std::string_view page_template, std::string header_json,
                   const ViewServerOptions& options)
    : feed_(std::make_shared<LiveFeed>(std::move(header_json))), recorder_(*feed_) {
  ViewContent content;
  content.page = viewer_page(page_template, ViewerSource::live);
  content.live = feed_;
  server_ = std::make_unique<ViewServer>(std::move(content), options);
}

}  // namespace overtake::view
