// The viewer's HTTP request handling (`overtake view`, the live view of `drive --live`): the
// bytes are read as the server reads requests from a connection (Beast's parser with the
// server's body limit, one request after another while they ask to keep the connection), and
// each request is judged as the server judges it: its Host header (view::host_allowed, for a
// server bound to loopback and to every address), its route (view::route_target), the
// websocket upgrade test and the Origin of an upgrade (view::same_origin). The server needs a
// socket; everything it decides from a request is here.
// A bad request is a Beast error code, never an exception: anything else is a finding.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include <boost/beast/core/error.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket/rfc6455.hpp>

#include "overtake/view/server.hpp"

namespace http = boost::beast::http;

namespace {

// As in src/view/server.cpp.
constexpr std::size_t kMaxRequestBodyBytes = 64 * 1024;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  overtake::view::ViewContent content;
  content.page = "<!doctype html>";
  content.replay = std::make_shared<const std::string>("OVTKRPLY");
  content.live = std::make_shared<const overtake::view::LiveFeed>("{}");

  std::string_view in(reinterpret_cast<const char*>(data), size);
  while (!in.empty()) {
    http::request_parser<http::string_body> parser;
    parser.body_limit(kMaxRequestBodyBytes);
    parser.eager(true);
    // All the bytes at once (eager: header and body in one call). need_more means the request
    // is not whole, and the server would wait for bytes that never come; calling put() again
    // without new bytes is outside Beast's contract (it asserts).
    boost::beast::error_code ec;
    const std::size_t used = parser.put(boost::asio::buffer(in.data(), in.size()), ec);
    if (ec || !parser.is_done()) return 0;  // a bad request (dropped) or an unfinished one
    in.remove_prefix(used);
    const http::request<http::string_body>& req = parser.get();
    const std::string_view target(req.target().data(), req.target().size());
    const auto header = [&req](http::field f) {
      const auto v = req[f];
      return std::string_view(v.data(), v.size());
    };
    (void)overtake::view::route_target(target, content);
    (void)overtake::view::host_allowed(header(http::field::host), "127.0.0.1");
    (void)overtake::view::host_allowed(header(http::field::host), "::");
    (void)boost::beast::websocket::is_upgrade(req);
    (void)overtake::view::same_origin(header(http::field::origin), header(http::field::host));
    if (!req.keep_alive()) break;
  }
  return 0;
}
