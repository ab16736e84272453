// Who the view server answers: a Host header that names this machine (localhost, 127.0.0.1,
// [::1] or the bound address), so that a DNS-rebinding page cannot read the replay; and on
// the live websocket, no Origin (not a browser) or the page's own origin only.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <vector>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/asio/connect.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#pragma GCC diagnostic pop

#include "overtake/view/server.hpp"

namespace overtake::view {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = net::ip::tcp;

TEST(ViewAccess, HostsThatNameThisMachine) {
  for (const char* host : {"localhost", "localhost:8080", "LocalHost:1", "127.0.0.1",
                           "127.0.0.1:8080", "[::1]", "[::1]:8080", "127.0.0.1:65535"}) {
    EXPECT_TRUE(host_allowed(host, "127.0.0.1")) << host;
  }
  for (const char* host :
       {"", "evil.example", "evil.example:8080", "localhost.evil.example", "127.0.0.1.nip.io",
        "localhost:", "localhost:80x", "localhost:99999", "127.0.0.1:8080:1", "[::1", "::1",
        "[::1]x", "127.0.0.2", "0.0.0.0", "localhost ", " localhost", "user@localhost"}) {
    EXPECT_FALSE(host_allowed(host, "127.0.0.1")) << host;
  }
  // The bound address, as given to --host, names this machine too.
  EXPECT_TRUE(host_allowed("192.0.2.7:8080", "192.0.2.7"));
  EXPECT_TRUE(host_allowed("viewer.lan:8080", "viewer.lan"));
  EXPECT_TRUE(host_allowed("[fd00::7]:8080", "fd00::7"));
  EXPECT_FALSE(host_allowed("192.0.2.8:8080", "192.0.2.7"));
  // Bound to every address: any address literal (DNS rebinding needs a name), no other name.
  EXPECT_TRUE(host_allowed("192.0.2.8:8080", "0.0.0.0"));
  EXPECT_TRUE(host_allowed("[fd00::8]:8080", "::"));
  EXPECT_FALSE(host_allowed("evil.example:8080", "0.0.0.0"));
  EXPECT_FALSE(host_allowed("evil.example", "::"));
}

TEST(ViewAccess, OriginsThatAreThePagesOwn) {
  EXPECT_TRUE(same_origin("http://127.0.0.1:8080", "127.0.0.1:8080"));
  EXPECT_TRUE(same_origin("http://LOCALHOST:8080", "localhost:8080"));
  EXPECT_TRUE(same_origin("http://[::1]:8080", "[::1]:8080"));
  EXPECT_TRUE(same_origin("http://localhost", "localhost"));
  EXPECT_TRUE(same_origin("http://localhost:80", "localhost"));
  EXPECT_TRUE(same_origin("http://localhost", "localhost:80"));
  for (const char* origin :
       {"http://evil.example", "http://evil.example:8080", "https://127.0.0.1:8080",
        "http://127.0.0.1:8081", "http://localhost:8080", "null", "", "127.0.0.1:8080",
        "http://127.0.0.1:8080/", "file://", "http://127.0.0.1:8080.evil.example"}) {
    EXPECT_FALSE(same_origin(origin, "127.0.0.1:8080")) << origin;
  }
}

// ---- over the socket ------------------------------------------------------------------------

struct Answer {
  unsigned status = 0;
  std::string body;
};

// A GET with this Host header (none when nullopt); the status and the body.
Answer get(std::uint16_t port, const std::string& target, const std::optional<std::string>& host) {
  net::io_context ioc;
  tcp::socket socket(ioc);
  socket.connect({net::ip::make_address("127.0.0.1"), port});
  http::request<http::empty_body> req{http::verb::get, target, 11};
  if (host) req.set(http::field::host, *host);
  req.keep_alive(false);
  http::write(socket, req);
  beast::flat_buffer buffer;
  http::response<http::string_body> res;
  beast::error_code ec;
  http::read(socket, buffer, res, ec);
  return {res.result_int(), res.body()};
}

class ViewAccessServer : public ::testing::Test {
 protected:
  void SetUp() override {
    ViewContent content;
    content.page = "<!doctype html>page";
    content.replay = std::make_shared<const std::string>("replay bytes");
    server_ = std::make_unique<ViewServer>(content, ViewServerOptions{"127.0.0.1", 0});
    auto feed = std::make_shared<LiveFeed>("{\"header\":1}");
    feed->close();
    ViewContent live;
    live.page = "<!doctype html>live page";
    live.live = feed;
    live_ = std::make_unique<ViewServer>(live, ViewServerOptions{"127.0.0.1", 0});
  }
  std::unique_ptr<ViewServer> server_;
  std::unique_ptr<ViewServer> live_;
};

TEST_F(ViewAccessServer, ServesTheReplayOnlyToHostsThatNameThisMachine) {
  const std::uint16_t port = server_->port();
  const std::string p = ":" + std::to_string(port);
  for (const std::string& host :
       std::vector<std::string>{"127.0.0.1" + p, "localhost" + p, "[::1]" + p, "localhost"}) {
    SCOPED_TRACE(host);
    EXPECT_EQ(get(port, "/", host).status, 200u);
    const Answer replay = get(port, "/replay.otr", host);
    EXPECT_EQ(replay.status, 200u);
    EXPECT_EQ(replay.body, "replay bytes");
  }
  for (const std::string& host :
       std::vector<std::string>{"evil.example" + p, "evil.example", "127.0.0.1.evil.example" + p}) {
    SCOPED_TRACE(host);
    for (const char* target : {"/", "/replay.otr", "/nothing-here"}) {
      const Answer a = get(port, target, host);
      EXPECT_EQ(a.status, 421u) << target;
      EXPECT_THAT(a.body, HasSubstr("localhost, 127.0.0.1, [::1]")) << target;
      EXPECT_THAT(a.body, Not(HasSubstr("replay bytes")));
    }
  }
  const Answer no_host = get(port, "/replay.otr", std::nullopt);
  EXPECT_EQ(no_host.status, 400u);
  EXPECT_THAT(no_host.body, HasSubstr("Host"));
}

// A websocket upgrade of /live with this Host and Origin (none when nullopt): 101 when it is
// accepted (and the first message, the header, then arrives), else the refusal's status and
// body. Written by hand: Beast's handshake does not keep a refusal's body.
Answer open_live(std::uint16_t port, const std::string& host,
                 const std::optional<std::string>& origin) {
  net::io_context ioc;
  tcp::socket socket(ioc);
  socket.connect({net::ip::make_address("127.0.0.1"), port});
  http::request<http::empty_body> req{http::verb::get, "/live", 11};
  req.set(http::field::host, host);
  if (origin) req.set(http::field::origin, *origin);
  req.set(http::field::upgrade, "websocket");
  req.set(http::field::connection, "Upgrade");
  req.set(http::field::sec_websocket_key, "dGhlIHNhbXBsZSBub25jZQ==");
  req.set(http::field::sec_websocket_version, "13");
  http::write(socket, req);
  beast::flat_buffer buffer;
  http::response_parser<http::string_body> parser;
  beast::error_code ec;
  http::read_header(socket, buffer, parser, ec);
  if (ec) return {};
  Answer out{parser.get().result_int(), {}};
  if (out.status == 101) {
    // The header message: one unmasked text frame, {"header":1}.
    const std::string want = "\x81\x0c{\"header\":1}";
    while (buffer.size() < want.size() && !ec) {
      buffer.commit(socket.read_some(buffer.prepare(64), ec));
    }
    EXPECT_EQ(beast::buffers_to_string(buffer.data()).substr(0, want.size()), want);
    return out;
  }
  http::read(socket, buffer, parser, ec);
  out.body = parser.get().body();
  return out;
}

TEST_F(ViewAccessServer, LiveWebsocketOnlyWithoutAnOriginOrFromItsOwnPage) {
  const std::uint16_t port = live_->port();
  const std::string p = ":" + std::to_string(port);
  EXPECT_EQ(get(port, "/", "127.0.0.1" + p).status, 200u);
  // No Origin: a program, not a browser page.
  EXPECT_EQ(open_live(port, "127.0.0.1" + p, std::nullopt).status, 101u);
  // The page's own origin, under each name it may be opened with.
  EXPECT_EQ(open_live(port, "127.0.0.1" + p, "http://127.0.0.1" + p).status, 101u);
  EXPECT_EQ(open_live(port, "localhost" + p, "http://localhost" + p).status, 101u);
  EXPECT_EQ(open_live(port, "[::1]" + p, "http://[::1]" + p).status, 101u);
  // Another origin, even on this machine.
  for (const std::string& origin : std::vector<std::string>{
           "http://evil.example", "http://evil.example" + p, "http://localhost" + p,
           "http://127.0.0.1:1", "null", "https://127.0.0.1" + p}) {
    SCOPED_TRACE(origin);
    const Answer a = open_live(port, "127.0.0.1" + p, origin);
    EXPECT_EQ(a.status, 403u);
    EXPECT_THAT(a.body, HasSubstr("Origin"));
  }
  // A foreign Host is refused before the Origin is looked at.
  EXPECT_EQ(open_live(port, "evil.example" + p, "http://evil.example" + p).status, 421u);
  EXPECT_EQ(open_live(port, "evil.example" + p, std::nullopt).status, 421u);
}

}  // namespace
}  // namespace overtake::view
