// `overtake serve` facing bad input: every frame gets its documented answer (manual, a pong,
// or nothing) and at most one warning line, and the connection and the server stay up.
// Websocket-level violations end that connection as RFC 6455 requires; the server stays up.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_support.hpp"

namespace overtake::protocol {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;
using namespace testing;  // NOLINT(google-build-using-namespace): the test helpers

constexpr std::string_view kControlStart = R"(42["control",)";
constexpr std::size_t kTwoMiB = std::size_t{2} << 20;

// One bad (or merely unusual) input and what the server must do with it.
struct Case {
  std::string name;
  std::string payload;
  bool binary = false;
  std::vector<std::string> replies;  // "control" matches any control frame
  int warnings = 1;                  // warning lines it causes; -1: any
};

std::string with(std::string text, std::string_view from, std::string_view to) {
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::logic_error("with(): not found: " + std::string(from));
  return text.replace(at, from.size(), to);
}

std::string repeated(std::string_view item, std::size_t n) {
  std::string out;
  out.reserve(item.size() * n + n);
  for (std::size_t i = 0; i < n; ++i) {
    if (i) out += ',';
    out += item;
  }
  return out;
}

std::vector<Case> bad_inputs() {
  const std::string t = std::string(kRecordedTelemetry);
  const std::string manual(kManual);
  const std::string points_100k = repeated("1", 100'000);
  const std::string points_10k = repeated("909.5", 10'000);
  const std::string rows_1001 = repeated("[0,1,2,3,4,5,6]", 1001);
  std::string big_telemetry =
      R"(42["telemetry",{"x":1,"pad":")" + std::string(kTwoMiB, 'a') + R"("}])";
  std::string deep_open = R"(42["telemetry",)" + std::string(100'000, '[');
  std::string deep_closed =
      R"(42["telemetry",)" + std::string(50'000, '[') + std::string(50'000, ']') + "]";
  return {
      // Telemetry that cannot be used: one warning, manual (the simulator waits for it).
      {"missing every key", R"(42["telemetry",{}])", false, {manual}},
      {"NaN as a string", with(t, R"("x":909.48)", R"("x":"NaN")"), false, {manual}},
      {"NaN as null", with(t, R"("x":909.48)", R"("x":null)"), false, {manual}},
      {"bare NaN token", with(t, R"("x":909.48)", R"("x":NaN)"), false, {manual}},
      {"bare Infinity token", with(t, R"("speed":0)", R"("speed":Infinity)"), false, {manual}},
      {"number overflowing a double", with(t, R"("speed":0)", R"("speed":1e999)"), false, {manual}},
      {"absurd magnitude", with(t, R"("s":124.8336)", R"("s":1e30)"), false, {manual}},
      {"boolean for a number", with(t, R"("yaw":0)", R"("yaw":true)"), false, {manual}},
      {"missing d", with(t, R"("d":6.164833,)", ""), false, {manual}},
      {"previous_path_x longer than _y",
       with(t, R"("previous_path_x":[])", R"("previous_path_x":[1,2])"),
       false,
       {manual}},
      {"previous_path_x not an array",
       with(t, R"("previous_path_x":[])", R"("previous_path_x":"[]")"),
       false,
       {manual}},
      {"null inside the previous path",
       with(t, R"("previous_path_x":[],"previous_path_y":[])",
            R"("previous_path_x":[1,null],"previous_path_y":[1,2])"),
       false,
       {manual}},
      {"100,000-point previous path",
       with(
           t, R"("previous_path_x":[],"previous_path_y":[])",
           R"("previous_path_x":[)" + points_100k + R"(],"previous_path_y":[)" + points_100k + "]"),
       false,
       {manual}},
      {"sensor row of 6 values", with(t, R"(85.3,2.012])", R"(85.3])"), false, {manual}},
      {"sensor row as an object",
       with(t, R"([0,775.99,1132.11,22.1,-0.3651,85.3,2.012])", R"({"id":0})"),
       false,
       {manual}},
      {"fractional car id", with(t, R"([0,775.99)", R"([1.5,775.99)"), false, {manual}},
      {"1001 sensor rows",
       with(t, R"([[0,775.99,1132.11,22.1,-0.3651,85.3,2.012]])", "[" + rows_1001 + "]"),
       false,
       {manual}},
      {"payload is an array", R"(42["telemetry",[1,2]])", false, {manual}},
      {"payload is a string", R"(42["telemetry","hello"])", false, {manual}},
      {"truncated telemetry", t.substr(0, 60), false, {manual}},
      {"event without payload", R"(42["telemetry"])", false, {manual}},
      {"empty event array", "42[]", false, {manual}},
      {"event that is not an array", R"(42{"a":1})", false, {manual}},
      {"event name not a string", R"(42[5,{}])", false, {manual}},
      {"bare 42", "42", false, {manual}},
      {"100,000 unclosed brackets", deep_open, false, {manual}},
      {"50,000 nested arrays as payload", deep_closed, false, {manual}},
      {"2 MiB telemetry (over the frame limit)", big_telemetry, false, {manual}},
      // Frames that are not a telemetry: one warning, no reply.
      {"a control sent to the planner", R"(42["control",{"next_x":[],"next_y":[]}])", false, {}},
      {"unknown event", R"(42["unknown",{}])", false, {}},
      {"empty text frame", "", false, {}},
      {"text that is not Engine.IO", "hello", false, {}},
      {"JSON without the 42 prefix", R"(["telemetry",null])", false, {}},
      {"unknown Engine.IO type", "7", false, {}},
      {"Socket.IO ack", R"(43["telemetry",null])", false, {}},
      {"empty Engine.IO message", "4", false, {}},
      {"binary frame holding a telemetry", t, true, {}},
      {"2 MiB of garbage text", std::string(kTwoMiB, 'x'), false, {}},
      {"2 MiB binary frame", std::string(kTwoMiB, '\0'), true, {}},
      // What the simulator normally sends besides telemetry: no warning.
      {"Engine.IO ping", "2", false, {"3"}, 0},
      {"Engine.IO probe ping", "2probe", false, {"3probe"}, 0},
      {"Engine.IO pong", "3", false, {}, 0},
      {"Engine.IO open", R"(0{"sid":"abc"})", false, {}, 0},
      {"Socket.IO connect", "40", false, {}, 0},
      {"the simulator's quit (41)", "41", false, {}, 0},
      {"the simulator's close (1)", "1", false, {}, 0},
      {"Engine.IO noop", "6", false, {}, 0},
      {"empty telemetry (null form)", std::string(kNullTelemetry), false, {manual}, 0},
      // Unusual but valid telemetry: the planner answers.
      {"keys reordered, extra keys, whitespace",
       "42[ \"telemetry\" , { \"sensor_fusion\" : [ ] , \"d\" : 6, \"s\" : 125, \"speed\" : 0, "
       "\"yaw\" : 0, "
       "\"y\" : 1128.67, \"x\" : 909.48, \"previous_path_y\" : [], \"previous_path_x\" : [], "
       "\"end_path_d\" : 0, "
       "\"end_path_s\" : 0, \"extra\" : {\"nested\": [1, 2]} } ]",
       false,
       {"control"},
       0},
      {"previous path at the 10,000-point limit",
       with(t, R"("previous_path_x":[],"previous_path_y":[])",
            R"("previous_path_x":[)" + points_10k + R"(],"previous_path_y":[)" + points_10k + "]"),
       false,
       {"control"},
       0},
      {"absurd but finite values",
       R"(42["telemetry",{"x":-9900000,"y":9900000,"yaw":9999999,"speed":9999999,"s":-9999999,"d":9999999,)"
       R"("previous_path_x":[9999999],"previous_path_y":[-9999999],"end_path_s":9999999,"end_path_d":-9999999,)"
       R"("sensor_fusion":[[0,9999999,-9999999,9999999,9999999,-9999999,9999999]]}])",
       false,
       {"control|manual"},
       -1},
  };
}

// Reads the frames that answer one bad input, then the control for the valid telemetry sent
// after it.
std::vector<std::string> replies_until_control(PlannerConnection& c, std::size_t expected_before) {
  std::vector<std::string> got;
  for (;;) {
    const auto f = c.receive(std::chrono::steady_clock::now() + 10s);
    if (!f) {
      got.push_back("<no reply within 10 s>");
      return got;
    }
    got.push_back(f->text);
    if (got.size() > expected_before && f->text.starts_with(kControlStart)) return got;
    if (got.size() > expected_before + 1) return got;
  }
}

bool matches(const std::string& frame, const std::string& want) {
  if (want == "control") return frame.starts_with(kControlStart);
  if (want == "control|manual") return frame.starts_with(kControlStart) || frame == kManual;
  return frame == want;
}

TEST(ProtocolServer, AnswersEachBadInputAsDocumentedAndStaysUp) {
  ServerFixture server;
  PlannerConnection c(server.planner_url(), quick_client());
  const std::string valid = start_telemetry();
  const auto cases = bad_inputs();
  ASSERT_GE(cases.size(), 30u);
  for (const Case& k : cases) {
    SCOPED_TRACE(k.name);
    const std::size_t warnings_before = server.log().warnings();
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    c.send(k.payload, deadline, k.binary);
    c.send(valid, deadline);  // the next valid telemetry still gets a control
    const auto got = replies_until_control(c, k.replies.size());
    ASSERT_EQ(got.size(), k.replies.size() + 1) << server.log().dump();
    for (std::size_t i = 0; i < k.replies.size(); ++i) {
      EXPECT_TRUE(matches(got[i], k.replies[i]))
          << "got " << excerpt(got[i]) << ", want " << k.replies[i];
    }
    EXPECT_THAT(got.back(), StartsWith(kControlStart));
    if (k.warnings >= 0) {
      EXPECT_EQ(server.log().warnings() - warnings_before, static_cast<std::size_t>(k.warnings))
          << server.log().dump();
    }
    ASSERT_TRUE(c.is_open());
  }
  // Every warning names the connection and says what was wrong on one line.
  for (const std::string& line : server.log().lines(LogLevel::warning)) {
    EXPECT_THAT(line, StartsWith("connection #1 "));
    EXPECT_EQ(line.find('\n'), std::string::npos);
    EXPECT_LT(line.size(), 300u) << line;
  }
  c.close();
  // The server is still up for the next connection.
  PlannerConnection again(server.planner_url(), quick_client());
  again.send(valid, std::chrono::steady_clock::now() + 5s);
  const auto f = again.receive(std::chrono::steady_clock::now() + 5s);
  ASSERT_TRUE(f);
  EXPECT_THAT(f->text, StartsWith(kControlStart));
}

void expect_server_answers(const ServerFixture& server) {
  PlannerConnection c(server.planner_url(), quick_client());
  c.send(start_telemetry(), std::chrono::steady_clock::now() + 5s);
  const auto f = c.receive(std::chrono::steady_clock::now() + 5s);
  ASSERT_TRUE(f);
  EXPECT_THAT(f->text, StartsWith(kControlStart));
  c.close();
}

// Waits (briefly) until the log has a line containing `text` (and `also`).
bool log_has(const ServerFixture& server, std::string_view text, std::string_view also = {}) {
  const auto deadline = std::chrono::steady_clock::now() + 3s;
  while (std::chrono::steady_clock::now() < deadline) {
    for (const auto& l : server.log().lines()) {
      if (l.find(text) != std::string::npos && l.find(also) != std::string::npos) return true;
    }
    std::this_thread::sleep_for(10ms);
  }
  return false;
}

struct RawCase {
  std::string name;
  std::function<void(RawClient&)> act;
  std::string log_text;  // the one line it causes
  bool warning = true;
};

TEST(ProtocolServer, WebsocketViolationsCloseThatConnectionOnly) {
  ServerFixture server("walkthrough", [](ServeOptions& o) { o.handshake_timeout = 300ms; });
  const std::string valid = start_telemetry();
  const std::vector<RawCase> cases = {
      {"TLS hello instead of HTTP",
       [](RawClient& r) { r.write(std::string("\x16\x03\x01\x02\x00\x01\x00", 7)); },
       "no websocket upgrade"},
      {"HTTP request without upgrade",
       [](RawClient& r) { r.write("GET / HTTP/1.1\r\nHost: x\r\n\r\n"); }, "no websocket upgrade"},
      {"silence instead of a handshake", [](RawClient&) {}, "no websocket upgrade"},
      {"unmasked client frame",
       [&](RawClient& r) {
         r.upgrade();
         r.write(RawClient::frame(0x81, valid, /*masked=*/false));
       },
       "websocket protocol error"},
      {"invalid UTF-8 in a text frame",
       [](RawClient& r) {
         r.upgrade();
         r.write(RawClient::frame(0x81, "42[\"telemetry\",\"\xc3\x28\"]"));
       },
       "websocket protocol error"},
      {"reserved opcode",
       [](RawClient& r) {
         r.upgrade();
         r.write(RawClient::frame(0x83, "x"));
       },
       "websocket protocol error"},
      {"reserved bit without an extension",
       [](RawClient& r) {
         r.upgrade();
         r.write(RawClient::frame(0xC1, "2"));
       },
       "websocket protocol error"},
      {"ping of 126 bytes",
       [](RawClient& r) {
         r.upgrade();
         r.write(RawClient::frame(0x89, std::string(126, 'p')));
       },
       "websocket protocol error"},
      {"fragmented ping",
       [](RawClient& r) {
         r.upgrade();
         r.write(RawClient::frame(0x09, "p"));
       },
       "websocket protocol error"},
      {"half a frame, then a reset",
       [&](RawClient& r) {
         r.upgrade();
         r.write(RawClient::frame(0x81, valid).substr(0, 40));
         r.close_abruptly();
       },
       "dropped", false},
      {"end of stream without a close frame",
       [](RawClient& r) {
         r.upgrade();
         r.close_gracefully();
       },
       "dropped", false},
      {"a frame claiming 2^62 bytes, then gone",
       [](RawClient& r) {
         r.upgrade();
         std::string header("\x81\xff", 2);
         header += std::string("\x40\x00\x00\x00\x00\x00\x00\x00", 8);
         header += std::string(4, '\0');
         r.write(header + std::string(100'000, 'a'));
         r.close_abruptly();
       },
       "dropped", false},
  };
  for (const RawCase& k : cases) {
    SCOPED_TRACE(k.name);
    std::string who;
    {
      RawClient raw(server.port());
      who = "(127.0.0.1:" + std::to_string(raw.local_port()) + ")";
      k.act(raw);
      if (k.warning) {
        EXPECT_TRUE(raw.closed_by_peer(3s)) << "the server must close this connection";
      }
    }
    EXPECT_TRUE(log_has(server, who, k.log_text)) << server.log().dump();
    // Exactly one line about it (besides the "open" line when the upgrade succeeded), at the
    // documented level.
    std::size_t about = 0;
    for (const auto& line : server.log().lines()) {
      about += line.find(who) != std::string::npos && !line.ends_with(" open");
    }
    EXPECT_EQ(about, 1u) << server.log().dump();
    std::size_t warnings = 0;
    for (const auto& line : server.log().lines(LogLevel::warning))
      warnings += line.find(who) != std::string::npos;
    EXPECT_EQ(warnings, k.warning ? 1u : 0u) << server.log().dump();
    expect_server_answers(server);
  }
}

TEST(ProtocolServer, UpgradeResponseCarriesNoSubprotocolOrExtension) {
  ServerFixture server;
  RawClient raw(server.port());
  // Offer both; the original simulator rejects a 101 that accepts either.
  const std::string head = raw.upgrade(
      "Sec-WebSocket-Protocol: chat\r\nSec-WebSocket-Extensions: permessage-deflate; "
      "client_max_window_bits\r\n");
  EXPECT_THAT(head, StartsWith("HTTP/1.1 101"));
  std::string lower = head;
  for (char& ch : lower) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  EXPECT_EQ(lower.find("sec-websocket-protocol"), std::string::npos) << head;
  EXPECT_EQ(lower.find("sec-websocket-extensions"), std::string::npos) << head;
  const auto version = lower.find("sec-websocket-version:");
  if (version != std::string::npos) {
    EXPECT_THAT(lower.substr(version), StartsWith("sec-websocket-version: 13"));
  }
  // Nothing is sent on connect: the first frame is the answer to our first telemetry.
  EXPECT_EQ(raw.read_frame(200ms), std::nullopt);
  raw.write(RawClient::frame(0x81, start_telemetry()));
  const auto reply = raw.read_frame(5s);
  ASSERT_TRUE(reply);
  EXPECT_THAT(*reply, StartsWith(kControlStart));
}

// `serve` serves no page, so an upgrade that carries an Origin header comes from a browser
// page (any site the user visits could open one: DNS rebinding needs not even that) and is
// refused, whatever the origin; the simulator and planner programs send no Origin.
TEST(ProtocolServer, RefusesWebsocketUpgradesFromBrowserPages) {
  ServerFixture server;
  const std::string self = "http://127.0.0.1:" + std::to_string(server.port());
  for (const std::string& origin :
       {std::string("http://evil.example"), self, std::string("null")}) {
    SCOPED_TRACE(origin);
    RawClient raw(server.port());
    const std::string who = "(127.0.0.1:" + std::to_string(raw.local_port()) + ")";
    const std::string head = raw.upgrade("Origin: " + origin + "\r\n");
    EXPECT_THAT(head, StartsWith("HTTP/1.1 403"));
    std::string body;
    EXPECT_TRUE(raw.closed_by_peer(3s, &body)) << "the server must close this connection";
    EXPECT_THAT(body, HasSubstr("Origin"));
    EXPECT_TRUE(log_has(server, who, "websocket upgrade refused: it comes from a browser page"))
        << server.log().dump();
    EXPECT_TRUE(log_has(server, who, origin));
  }
  // Without an Origin, as the original simulator and our client connect: accepted.
  RawClient raw(server.port());
  EXPECT_THAT(raw.upgrade(), StartsWith("HTTP/1.1 101"));
  raw.write(RawClient::frame(0x81, start_telemetry()));
  const auto reply = raw.read_frame(5s);
  ASSERT_TRUE(reply);
  EXPECT_THAT(*reply, StartsWith(kControlStart));
  EXPECT_EQ(server.log().lines(LogLevel::warning).size(), 3u) << server.log().dump();
}

// A simulator that closes normally (a close frame) and goes at once, without waiting for the
// server's close frame: logged as closed by the peer, not as a protocol error ("Transport
// endpoint is not connected", met while tearing the connection down).
TEST(ProtocolServer, APeerThatClosesNormallyAndGoesIsLoggedAsClosed) {
  ServerFixture server;
  for (int attempt = 0; attempt < 5; ++attempt) {
    SCOPED_TRACE(attempt);
    std::string who;
    {
      RawClient raw(server.port());
      who = "(127.0.0.1:" + std::to_string(raw.local_port()) + ")";
      raw.upgrade();
      raw.write(RawClient::frame(0x88, std::string("\x03\xe8", 2)));  // close, code 1000
      raw.close_gracefully();
    }
    EXPECT_TRUE(log_has(server, who, "closed by the peer (close code 1000)"))
        << server.log().dump();
    for (const auto& line : server.log().lines(LogLevel::warning)) {
      EXPECT_EQ(line.find(who), std::string::npos) << line;
    }
  }
}

TEST(ProtocolServer, AcceptsTheUpgradeOnAnyPath) {
  ServerFixture server;
  for (const char* path : {"/", "/socket.io/?EIO=4&transport=websocket", "/anything/at/all?x=1"}) {
    auto url = server.planner_url();
    url.target = path;
    PlannerConnection c(url, quick_client());
    c.send(kNullTelemetry, std::chrono::steady_clock::now() + 5s);
    const auto f = c.receive(std::chrono::steady_clock::now() + 5s);
    ASSERT_TRUE(f) << path;
    EXPECT_EQ(f->text, kManual) << path;
  }
}

// One planner state per connection: two connections fed the same telemetries get the same
// answers, whatever the other one has seen.
TEST(ProtocolServer, EachConnectionHasItsOwnPlanner) {
  ServerFixture server;
  const std::string t = start_telemetry();
  const auto round_trip = [&](PlannerConnection& c) {
    c.send(t, std::chrono::steady_clock::now() + 5s);
    const auto f = c.receive(std::chrono::steady_clock::now() + 5s);
    return f ? f->text : std::string("<none>");
  };
  PlannerConnection a(server.planner_url(), quick_client());
  std::vector<std::string> a_replies;
  for (int i = 0; i < 10; ++i) a_replies.push_back(round_trip(a));
  EXPECT_NE(a_replies.front(), a_replies.back())
      << "the walkthrough ramps its speed cycle by cycle";
  PlannerConnection b(server.planner_url(), quick_client());
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(round_trip(b), a_replies[static_cast<std::size_t>(i)]) << i;
    (void)round_trip(a);  // a moves on meanwhile
  }
  b.close();
  // Reconnecting starts a fresh planner.
  PlannerConnection c(server.planner_url(), quick_client());
  EXPECT_EQ(round_trip(c), a_replies.front());
}

TEST(ProtocolServer, StatusLineOnceASecondAndListensOnLoopbackByDefault) {
  EXPECT_EQ(ServeOptions{}.host, "127.0.0.1");
  EXPECT_EQ(ServeOptions{}.port, 4567);
  ServerFixture server("walkthrough", [](ServeOptions& o) { o.status_lines = true; });
  EXPECT_TRUE(log_has(server, "listening on ws://127.0.0.1:"));
  PlannerConnection c(server.planner_url(), quick_client());
  const auto until = std::chrono::steady_clock::now() + 1300ms;
  while (std::chrono::steady_clock::now() < until) {
    c.send(start_telemetry(), until + 5s);
    ASSERT_TRUE(c.receive(until + 5s));
    std::this_thread::sleep_for(20ms);
  }
  EXPECT_TRUE(log_has(server, "status: 1 connection, ")) << server.log().dump();
  const auto lines = server.log().lines();
  const auto status = std::find_if(lines.begin(), lines.end(),
                                   [](const std::string& l) { return l.starts_with("status:"); });
  ASSERT_NE(status, lines.end());
  EXPECT_THAT(*status, HasSubstr("cycles/s"));
  EXPECT_THAT(*status, HasSubstr("mph, lane 1, planner median"));
}

TEST(ProtocolServer, RefusesUnknownPolicyAndBusyPort) {
  const auto track = default_track();
  PlannerSetup setup;
  setup.line = std::shared_ptr<const core::ReferenceLine>(track, &track->line);
  setup.policy = "no-such-policy";
  net::io_context ioc;
  ServeOptions opts;
  opts.port = 0;
  EXPECT_THROW(run_server(ioc, setup, opts), std::invalid_argument);

  ServerFixture server;
  setup.policy = "walkthrough";
  opts.port = server.port();
  opts.log = [](LogLevel, std::string_view) {};
  try {
    run_server(ioc, setup, opts);
    ADD_FAILURE() << "listening on a busy port must fail";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("cannot listen on 127.0.0.1:" + std::to_string(server.port())));
  }
}

}  // namespace
}  // namespace overtake::protocol
