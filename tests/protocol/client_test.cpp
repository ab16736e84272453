// `overtake sim --planner`: our simulator facing planners that misbehave (small fake servers
// in this file: stalls, closes, malformed replies, second replies that put a lock-step run out
// of step), the original's upgrade request, connection retries, the scorecard, and a planner
// written the old way (cut from '[' to '}', "null" means empty), in lock-step and in real time.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "original_planner.hpp"
#include "overtake/app/cli.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/run/config.hpp"
#include "test_support.hpp"

namespace overtake::protocol {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;
using namespace testing;  // NOLINT(google-build-using-namespace): the test helpers

// A fake planner that drives well: the walkthrough policy behind the codec. `misbehave` may
// replace the answer to any message.
FakeBehaviour walkthrough_planner(
    std::function<std::optional<FakeAction>(int index, const std::string& good)> misbehave = {}) {
  const auto track = default_track();
  auto policy = std::shared_ptr<planner::Policy>(
      planner::make_policy("walkthrough", track->line, run::default_config().planner));
  return [policy, track, misbehave](std::string_view message, int index) {
    if (!is_event(message)) return FakeAction{};  // e.g. our answer to its ping
    std::string good(kManual);
    const auto t = parse_telemetry(message);
    if (t.ok() && t.value()) good = format_control(policy->plan(*t.value()).path);
    if (misbehave) {
      if (auto a = misbehave(index, good)) return *a;
    }
    return FakeAction{{good}};
  };
}

// Drives `world` for `seconds` in lock-step against the planner at `url`.
sim::RunReport lock_step(const std::string& url, double seconds, LogCapture& log,
                         std::chrono::milliseconds reply_timeout = 3s, int steps_per_call = 0) {
  const auto track = default_track();
  sim::World world(track->map, track->line, run::default_config().world,
                   sim::TrafficProfile::faithful, 3);
  ClientOptions o = quick_client(&log);
  o.reply_timeout = reply_timeout;
  PlannerConnection c(parse_planner_url(url).value(), o);
  sim::RunOptions run;
  run.duration_s = seconds;
  run.seed = 3;
  if (steps_per_call > 0) run.steps_per_call = steps_per_call;
  sim::RunReport report = run_lock_step(world, c, o, run);
  c.close();
  return report;
}

std::filesystem::path temp_file(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         ("overtake-protocol-" + std::to_string(::getpid()) + "-" + name + ".json");
}

int run_cli(std::vector<std::string> args) {
  args.insert(args.begin(), "overtake");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  return app::run_cli(static_cast<int>(argv.size()), argv.data());
}

TEST(ProtocolClient, StallEndsTheRunWithAMessageAndTheReportIsKept) {
  FakePlanner planner(
      walkthrough_planner([](int index, const std::string&) -> std::optional<FakeAction> {
        if (index >= 100) return FakeAction{};  // no reply, ever
        return std::nullopt;
      }));
  const auto json_path = temp_file("stall");
  const auto t0 = std::chrono::steady_clock::now();
  const int rc = run_cli({"sim", "--planner", planner.url(), "--minutes", "1", "--reply-timeout",
                          "0.3", "--json", json_path.string(), "--quiet"});
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 5s);
  EXPECT_EQ(rc, base::kExitFailure);
  const auto j = nlohmann::json::parse(base::read_file(json_path));
  std::filesystem::remove(json_path);
  const std::string why = j["ended_early"].get<std::string>();
  EXPECT_THAT(why, StartsWith("planner failed at t = "));
  EXPECT_THAT(why, HasSubstr("the planner stalled: no reply within 0.3 s"));
  EXPECT_EQ(j["planner_cycles"], 100);
  EXPECT_GT(j["duration_s"].get<double>(), 1.0);
  EXPECT_LT(j["duration_s"].get<double>(), 60.0);
  EXPECT_GT(j["distance_miles"].get<double>(), 0.0);
}

TEST(ProtocolClient, CloseAndDropEndTheRunWithAMessage) {
  for (const bool graceful : {true, false}) {
    SCOPED_TRACE(graceful ? "close frame" : "TCP dropped");
    FakePlanner planner(walkthrough_planner(
        [graceful](int index, const std::string& good) -> std::optional<FakeAction> {
          if (index != 60) return std::nullopt;
          FakeAction a{{good}};
          (graceful ? a.close : a.drop) = true;
          return a;
        }));
    LogCapture log;
    const auto report = lock_step(planner.url(), 60.0, log);
    EXPECT_THAT(sim::ended_early_text(report.outcome), StartsWith("planner failed at t = "));
    EXPECT_THAT(sim::ended_early_text(report.outcome),
                HasSubstr(graceful ? "the planner closed the connection normally (close code 1000)"
                                   : "the planner dropped the connection"));
    EXPECT_EQ(report.planner_cycles, 61);  // the reply that came with the close counts
    EXPECT_GT(report.duration_s, 0.0);
  }
}

TEST(ProtocolClient, MalformedRepliesEndTheRunSayingWhat) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"(42["control",{"next_x":[1,2],"next_y":[1,null]}])",
       "malformed reply: 'next_y'[1] is null, not a number"},
      {R"(42["control",{"next_x":[1,2],"next_y":[1]}])",
       "malformed reply: 'next_y' has 1 points, fewer than the 2 of 'next_x'"},
      {R"(42["control",{"next_x":[NaN],"next_y":[1]}])",
       "malformed reply: the event is not valid JSON"},
      {R"(42["control",{"next_y":[1]}])", "malformed reply: 'next_x' is missing"},
      {R"(42["steer",{}])", "malformed reply: unexpected event \"steer\""},
      {"hello", "malformed reply: not an Engine.IO packet"},
      {"", "malformed reply: not an Engine.IO packet"},
      {"44{}", "malformed reply: not a Socket.IO event"},
      {"1", "the planner closed its session (1)"},
  };
  for (const auto& [bad, message] : cases) {
    SCOPED_TRACE(bad);
    FakePlanner planner(
        walkthrough_planner([&bad](int index, const std::string&) -> std::optional<FakeAction> {
          if (index == 25) return FakeAction{{bad}};
          return std::nullopt;
        }));
    LogCapture log;
    const auto report = lock_step(planner.url(), 60.0, log);
    EXPECT_THAT(sim::ended_early_text(report.outcome), StartsWith("planner failed at t = "));
    EXPECT_THAT(sim::ended_early_text(report.outcome), HasSubstr(message));
    EXPECT_EQ(report.planner_cycles, 25);
  }
}

TEST(ProtocolClient, BinaryReplyIsMalformed) {
  FakePlanner planner([](std::string_view, int) {
    FakeAction a{{std::string(kManual)}};
    a.binary = true;
    return a;
  });
  LogCapture log;
  const auto report = lock_step(planner.url(), 10.0, log);
  EXPECT_THAT(sim::ended_early_text(report.outcome), HasSubstr("malformed reply"));
}

// A planner that closes normally (a close frame, code 1000) and exits without waiting for
// our close frame: the run ends saying that it closed, not with the socket error that tearing
// the connection down then meets ("Transport endpoint is not connected", "Connection reset").
TEST(ProtocolClient, ANormalCloseIsReportedAsSuchEvenWhenThePlannerIsGoneAtOnce) {
  for (const auto exit_after : {0ms, 30ms}) {
    for (int attempt = 0; attempt < 3; ++attempt) {
      SCOPED_TRACE("exits " + std::to_string(exit_after.count()) + " ms after its close frame");
      FakePlanner planner(walkthrough_planner(
          [exit_after](int index, const std::string& good) -> std::optional<FakeAction> {
            if (index != 30) return std::nullopt;
            FakeAction a{{good}};
            a.close_then_exit = true;
            a.exit_after = exit_after;
            return a;
          }));
      LogCapture log;
      const auto report = lock_step(planner.url(), 60.0, log);
      EXPECT_THAT(sim::ended_early_text(report.outcome),
                  HasSubstr("the planner closed the connection normally (close code 1000)"));
    }
  }
}

// How a planner answers one telemetry twice, the second copy a little late. Each must put the
// run out of step, every time, wherever the copy lands among our next telemetries.
struct TwiceCase {
  std::string name;
  std::function<FakeAction(const std::string& good)> twice;   // the answer to the telemetry
  std::function<FakeAction(const std::string& good)> normal;  // to every other one
  bool in_handler = true;  // the copy is sent before the planner reads on: found at once
};

std::vector<TwiceCase> twice_cases() {
  const auto plain = [](const std::string& good) { return FakeAction{{good}}; };
  // Answers from a timer while the planner reads on, so that it answers our pings first.
  const auto pong_first = [](const std::string& good) {
    FakeAction a;
    a.later = {{1ms, good}};
    return a;
  };
  return {
      {"the copy right behind the reply, in one write",
       [](const std::string& good) {
         FakeAction a{{good, good}};
         a.one_write = true;
         return a;
       },
       plain},
      {"the handler sleeps 5 ms, then sends the copy",
       [](const std::string& good) {
         FakeAction a{{good}};
         a.pause = 5ms;
         a.after_pause = {good};
         return a;
       },
       plain},
      {"a timer sends the copy 5 ms later while the planner reads on",
       [](const std::string& good) {
         FakeAction a{{good}};
         a.later = {{5ms, good}};
         return a;
       },
       plain, false},
      {"the copy 3 ms after the reply, each answer taking 2 ms",
       [](const std::string& good) {
         FakeAction a;
         a.pause = 2ms;
         a.after_pause = {good};
         a.later = {{3ms, good}};
         return a;
       },
       [](const std::string& good) {
         FakeAction a;
         a.pause = 2ms;  // each answer takes a little while; pings wait for it
         a.after_pause = {good};
         return a;
       },
       false},
      {"a planner that answers pings before telemetry, copy 5 ms late",
       [](const std::string& good) {
         FakeAction a;
         a.later = {{1ms, good}, {6ms, good}};
         return a;
       },
       pong_first, false},
  };
}

TEST(ProtocolClient, ALateSecondReplyPutsTheRunOutOfStepEveryTime) {
  constexpr int kCycles = 150;  // one step per reply: message i answers cycle i
  for (const TwiceCase& c : twice_cases()) {
    for (const int twice_at : {20, 41, 77, kCycles - 1}) {
      SCOPED_TRACE(c.name + ", twice at message " + std::to_string(twice_at));
      FakePlanner planner(walkthrough_planner(
          [&c, twice_at](int index, const std::string& good) -> std::optional<FakeAction> {
            return index == twice_at ? c.twice(good) : c.normal(good);
          }));
      LogCapture log;
      const auto report = lock_step(planner.url(), 0.02 * kCycles, log, 3s, 1);
      EXPECT_THAT(sim::ended_early_text(report.outcome), StartsWith("planner failed at t = "))
          << log.dump();
      EXPECT_THAT(sim::ended_early_text(report.outcome),
                  HasSubstr("out of step: the planner replied twice"));
      if (c.in_handler) {
        EXPECT_LE(report.planner_cycles, twice_at + 2) << "found at once";
      }
    }
  }
}

// The checks that find a second reply do not trip on planners that behave, however they
// time their answers, nor on a planner whose answers are all the same.
TEST(ProtocolClient, PlannersThatAnswerOnceAreNeverOutOfStep) {
  const std::vector<std::pair<std::string, FakeBehaviour>> planners = {
      {"answers at once", walkthrough_planner()},
      {"answers pings before telemetry",
       walkthrough_planner([](int, const std::string& good) -> std::optional<FakeAction> {
         FakeAction a;
         a.later = {{2ms, good}};
         return a;
       })},
      {"always the same empty path",
       [](std::string_view, int) {
         return FakeAction{{R"(42["control",{"next_x":[],"next_y":[]}])"}};
       }},
      {"always manual", [](std::string_view, int) { return FakeAction{{std::string(kManual)}}; }},
  };
  for (const auto& [name, behaviour] : planners) {
    SCOPED_TRACE(name);
    FakePlanner planner(behaviour);
    LogCapture log;
    const auto t0 = std::chrono::steady_clock::now();
    const auto report = lock_step(planner.url(), 3.0, log);
    EXPECT_EQ(sim::ended_early_text(report.outcome), "") << log.dump();
    EXPECT_EQ(log.warnings(), 0u) << log.dump();
    EXPECT_DOUBLE_EQ(report.duration_s, 3.0);
    // These planners write without TCP_NODELAY, so Nagle's algorithm holds the second of
    // their two frames a cycle (reply, pong) until the first is acknowledged: the client
    // acknowledges at once, else each of the ~75 cycles would wait for a delayed ACK
    // (about 40 ms: 3 s in all).
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 1500ms);
  }
}

// Engine.IO chatter from a planner (a ping, a Socket.IO connect) is answered or ignored; a
// manual reply to a full telemetry keeps the queued path.
TEST(ProtocolClient, PlannerChatterAndManualRepliesDoNotEndTheRun) {
  FakePlanner planner(
      walkthrough_planner([](int index, const std::string& good) -> std::optional<FakeAction> {
        if (index == 0) return FakeAction{{"40", "2probe", good}};
        if (index == 30) return FakeAction{{std::string(kManual)}};
        return std::nullopt;
      }));
  LogCapture log;
  const auto report = lock_step(planner.url(), 20.0, log);
  EXPECT_EQ(sim::ended_early_text(report.outcome), "");
  const auto got = planner.received();
  EXPECT_NE(std::find(got.begin(), got.end(), "3probe"), got.end()) << "the ping is answered";
  EXPECT_EQ(log.warnings(), 0u) << log.dump();
  EXPECT_GT(report.distance_m, 100.0);
}

// The scorecard of `sim` says so and names the planner's address (with --name, the name too).
TEST(ProtocolClient, TheScorecardNamesSimAndThePlannersAddress) {
  ServerFixture server;
  const std::string address = server.url() + "/socket.io/?EIO=4&transport=websocket";
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(run_cli({"sim", "--planner", server.url(), "--minutes", "0.05", "--quiet"}),
            base::kExitOk);
  EXPECT_THAT(::testing::internal::GetCapturedStdout(),
              StartsWith("overtake sim: planner at " + address +
                         ", faithful traffic, seed 1, map builtin:default\n"));
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(run_cli({"sim", "--planner", server.url(), "--name", "mine", "--minutes", "0.05",
                     "--seed", "4", "--quiet"}),
            base::kExitOk);
  EXPECT_THAT(
      ::testing::internal::GetCapturedStdout(),
      StartsWith("overtake sim: planner mine at " + address + ", faithful traffic, seed 4"));
}

TEST(ProtocolClient, SendsTheOriginalsUpgradeRequestAndSpeaksFirst) {
  FakePlanner planner(walkthrough_planner());
  LogCapture log;
  (void)lock_step(planner.url(), 1.0, log);
  const std::string req = planner.upgrade_request();
  EXPECT_THAT(req, StartsWith("GET /socket.io/?EIO=4&transport=websocket HTTP/1.1\r\n"));
  std::string lower = req;
  for (char& ch : lower) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  EXPECT_THAT(lower, HasSubstr("upgrade: websocket"));
  EXPECT_THAT(lower, HasSubstr("sec-websocket-version: 13"));
  EXPECT_THAT(lower, HasSubstr("host: 127.0.0.1:"));
  for (const char* absent :
       {"user-agent", "origin", "cookie", "sec-websocket-protocol", "sec-websocket-extensions"}) {
    EXPECT_THAT(lower, Not(HasSubstr(absent))) << req;
  }
  const auto got = planner.received();
  ASSERT_FALSE(got.empty());
  const auto first = parse_telemetry(got[0]);
  ASSERT_TRUE(first.ok()) << first.error();
  EXPECT_TRUE(first.value().has_value()) << "the first message is a full telemetry";
}

TEST(ProtocolClient, RetriesUntilThePlannerIsUpAndGivesUpAfterTheTimeout) {
  std::uint16_t port = 0;
  {
    net::io_context ioc;
    tcp::acceptor probe(ioc, {net::ip::make_address("127.0.0.1"), 0});
    port = probe.local_endpoint().port();
  }
  const std::string url = "ws://127.0.0.1:" + std::to_string(port) + "/";
  // Nobody listens: it gives up after the timeout, saying so.
  ClientOptions o = quick_client();
  o.connect_timeout = 400ms;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    PlannerConnection c(parse_planner_url(url).value(), o);
    ADD_FAILURE() << "connected to nobody";
  } catch (const ConnectionError& e) {
    EXPECT_THAT(e.what(), HasSubstr("cannot connect to the planner at " + url + " within 0.4 s"));
  }
  const auto waited = std::chrono::steady_clock::now() - t0;
  EXPECT_GE(waited, 300ms);
  EXPECT_LT(waited, 2s);
  // The planner comes up while the client is retrying.
  std::unique_ptr<FakePlanner> late;
  std::thread starter([&] {
    std::this_thread::sleep_for(300ms);
    late = std::make_unique<FakePlanner>(walkthrough_planner(), port);
  });
  o.connect_timeout = 5s;
  {
    PlannerConnection c(parse_planner_url(url).value(), o);
    EXPECT_TRUE(c.is_open());
    starter.join();
    c.close();
  }
}

TEST(ProtocolClient, RejectsBadPlannerUrls) {
  EXPECT_EQ(parse_planner_url("ws://127.0.0.1:4567").value().target,
            "/socket.io/?EIO=4&transport=websocket");
  EXPECT_EQ(parse_planner_url("ws://localhost").value().port, "4567");
  EXPECT_EQ(parse_planner_url("ws://[::1]:80/x?y").value().host, "::1");
  EXPECT_EQ(parse_planner_url("ws://h:1?EIO=4").value().target, "/?EIO=4");
  EXPECT_EQ(to_string(parse_planner_url("ws://[::1]:80/x").value()), "ws://[::1]:80/x");
  for (const char* bad : {"http://127.0.0.1:4567", "wss://127.0.0.1", "ws://", "ws://:80",
                          "ws://h:0", "ws://h:70000", "ws://h:x/", "ws://[::1", "127.0.0.1:4567"}) {
    EXPECT_FALSE(parse_planner_url(bad).ok()) << bad;
  }
  EXPECT_EQ(run_cli({"sim", "--planner", "http://127.0.0.1:1", "--quiet"}), base::kExitUsage);
}

// A planner over the protocol answers points only: overtake cannot know how it planned, so
// its cycles are counted by no plan status, its report's plan_status is null (not "normal"),
// and the scorecard prints no plan status line; in lock-step and in real time (where a manual
// reply to a full telemetry counts as a cycle too).
TEST(ProtocolClient, ARemotePlannersPlanStatusIsUnknown) {
  {
    FakePlanner planner(walkthrough_planner());
    const auto json_path = temp_file("unknown-status");
    ::testing::internal::CaptureStdout();
    const int rc = run_cli({"sim", "--planner", planner.url(), "--minutes", "0.1", "--json",
                            json_path.string(), "--quiet"});
    const std::string text = ::testing::internal::GetCapturedStdout();
    ASSERT_EQ(rc, base::kExitOk);
    const auto j = nlohmann::json::parse(base::read_file(json_path));
    std::filesystem::remove(json_path);
    ASSERT_TRUE(j.contains("plan_status"));
    EXPECT_TRUE(j["plan_status"].is_null()) << j["plan_status"];
    EXPECT_GT(j["planner_cycles"].get<long>(), 100);
    EXPECT_THAT(text, HasSubstr("planner time"));
    EXPECT_THAT(text, Not(HasSubstr("plan status")));
  }
  {
    FakePlanner planner(walkthrough_planner());
    LogCapture log;
    const auto report = lock_step(planner.url(), 3.0, log);
    EXPECT_EQ(sim::ended_early_text(report.outcome), "") << log.dump();
    EXPECT_GT(report.planner_cycles, 50);
    EXPECT_EQ(report.plan_status_unknown_cycles, report.planner_cycles);
    EXPECT_EQ(report.plan_status_cycles, core::PlanStatusCounts{});
    EXPECT_FALSE(report.plan_status_known());
  }
  {
    FakePlanner planner(
        walkthrough_planner([](int index, const std::string&) -> std::optional<FakeAction> {
          if (index == 10) return FakeAction{{std::string(kManual)}};
          return std::nullopt;
        }));
    const auto track = default_track();
    sim::World world(track->map, track->line, run::default_config().world,
                     sim::TrafficProfile::faithful, 3);
    LogCapture log;
    const ClientOptions o = quick_client(&log);
    PlannerConnection c(parse_planner_url(planner.url()).value(), o);
    sim::RunOptions run;
    run.duration_s = 1.0;
    const sim::RunReport report = run_realtime(world, c, o, run);
    c.close();
    EXPECT_EQ(sim::ended_early_text(report.outcome), "") << log.dump();
    EXPECT_GT(report.planner_cycles, 10);
    EXPECT_EQ(report.plan_status_unknown_cycles, report.planner_cycles);
    EXPECT_FALSE(report.plan_status_known());
  }
}

// The old-style planner (tests/protocol/original_planner.hpp) reads every full telemetry our
// client sends, in lock-step, and recognises the null ones of a real-time run.
TEST(ProtocolOriginalConvention, OldStylePlannerReadsOurClientInLockStep) {
  OriginalPlannerStats stats;
  sim::RunReport report;
  {
    FakePlanner planner([&stats](std::string_view m, int) {
      return FakeAction{{original_planner_answer(m, stats)}};
    });
    LogCapture log;
    report = lock_step(planner.url(), 30.0, log);
  }
  EXPECT_EQ(sim::ended_early_text(report.outcome), "");
  EXPECT_EQ(stats.full, report.planner_cycles);
  EXPECT_EQ(stats.unreadable, 0);
}

TEST(ProtocolOriginalConvention, OldStylePlannerRecognisesNullTelemetryInRealTime) {
  OriginalPlannerStats stats;
  sim::RunReport report;
  {
    FakePlanner planner([&stats](std::string_view m, int) {
      return FakeAction{{original_planner_answer(m, stats)}};
    });
    const auto track = default_track();
    sim::World world(track->map, track->line, run::default_config().world,
                     sim::TrafficProfile::faithful, 3);
    LogCapture log;
    const ClientOptions o = quick_client(&log);
    PlannerConnection c(parse_planner_url(planner.url()).value(), o);
    sim::RunOptions run;
    run.duration_s = 1.5;
    const auto t0 = std::chrono::steady_clock::now();
    report = run_realtime(world, c, o, run);
    const auto wall = std::chrono::steady_clock::now() - t0;
    EXPECT_GE(wall, 1400ms) << "real time: 50 steps a second";
    EXPECT_LT(wall, 3s);
    EXPECT_EQ(world.steps(), 75);
    c.close();
    EXPECT_EQ(log.warnings(), 0u) << log.dump();
  }
  EXPECT_EQ(sim::ended_early_text(report.outcome), "");
  EXPECT_GT(stats.full, 20);
  EXPECT_GT(stats.empty, 0) << "a fast planner is sent 42[\"telemetry\",null] when nothing stepped";
  EXPECT_EQ(stats.unreadable, 0);
  EXPECT_EQ(report.planner_cycles, stats.full);
  EXPECT_GT(report.distance_m, 5.0);
}

TEST(ProtocolClient, RealTimeStallEndsTheRunWhileTheWorldKeepsStepping) {
  FakePlanner planner(
      walkthrough_planner([](int index, const std::string&) -> std::optional<FakeAction> {
        if (index >= 10) return FakeAction{};
        return std::nullopt;
      }));
  const auto track = default_track();
  sim::World world(track->map, track->line, run::default_config().world,
                   sim::TrafficProfile::faithful, 3);
  LogCapture log;
  ClientOptions o = quick_client(&log);
  o.reply_timeout = 300ms;
  PlannerConnection c(parse_planner_url(planner.url()).value(), o);
  sim::RunOptions run;
  run.duration_s = 30.0;
  const sim::RunReport report = run_realtime(world, c, o, run);
  EXPECT_THAT(sim::ended_early_text(report.outcome),
              HasSubstr("the planner stalled: no reply within 0.3 s"));
  EXPECT_GE(report.duration_s, 0.3);  // the world went on for the whole wait
  EXPECT_LT(report.duration_s, 5.0);
}

}  // namespace
}  // namespace overtake::protocol
