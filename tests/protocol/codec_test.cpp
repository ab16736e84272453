// The message codec: numbers printed as the original prints them (and consistent with
// core::wire_round), recorded messages, exact bytes of our telemetry, control round trips,
// and rejection of bad messages with a reason.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <limits>
#include <random>

#include <nlohmann/json.hpp>

#include "original_planner.hpp"
#include "overtake/core/units.hpp"
#include "overtake/core/wire_number.hpp"
#include "overtake/protocol/codec.hpp"
#include "overtake/run/config.hpp"
#include "overtake/sim/world.hpp"
#include "test_support.hpp"

namespace overtake::protocol {
namespace {

using ::testing::HasSubstr;
using testing::kRecordedTelemetry;

// ---- numbers ----------------------------------------------------------------------------

TEST(ProtocolNumbers, PrintLikeTheOriginal) {
  const std::vector<std::pair<double, std::string>> cases = {
      {0.0, "0"},
      {-0.0, "0"},  // C# (Mono) prints negative zero as 0
      {49.0, "49"},
      {100.0, "100"},
      {909.48, "909.48"},
      {909.48250105225, "909.4825"},  // protocol.md's example
      {124.8336, "124.8336"},
      {6.164833, "6.164833"},
      {-0.3651, "-0.3651"},
      {0.1, "0.1"},
      {1.0 / 3.0, "0.3333333"},
      {1234567.0, "1234567"},
      {9999999.0, "9999999"},
      {9999999.5, "1E+07"},  // rounds up to 1e7 as a float
      {1e7, "1E+07"},
      {12345678.9, "1.234568E+07"},
      {16777217.0, "1.677722E+07"},
      {-123.456, "-123.456"},
      {0.0001, "0.0001"},
      {0.000123456789, "0.0001234568"},
      {1e-5, "1E-05"},
      {-3.5e-6, "-3.5E-06"},
      {2.5e-7, "2.5E-07"},
      {1e38, "1E+38"},
      {-1.5e20, "-1.5E+20"},
  };
  for (const auto& [value, text] : cases) EXPECT_EQ(format_wire_number(value), text) << value;
}

TEST(ProtocolNumbers, NonFiniteAsCSharpPrintsThem) {
  EXPECT_EQ(format_wire_number(std::numeric_limits<double>::quiet_NaN()), "NaN");
  EXPECT_EQ(format_wire_number(std::numeric_limits<double>::infinity()), "Infinity");
  EXPECT_EQ(format_wire_number(-std::numeric_limits<double>::infinity()), "-Infinity");
  EXPECT_EQ(format_wire_number(1e39), "Infinity");  // beyond float range
}

// Parsing the printed text gives exactly core::wire_round(v), across every magnitude.
TEST(ProtocolNumbers, ParsedTextIsWireRound) {
  std::mt19937_64 rng(20240607);
  std::uniform_real_distribution<double> mantissa(1.0, 10.0);
  std::uniform_int_distribution<int> exponent(-44, 37);
  int exponent_forms = 0;
  for (int i = 0; i < 100'000; ++i) {
    double v = mantissa(rng) * std::pow(10.0, exponent(rng));
    if (i % 2) v = -v;
    if (i % 97 == 0) v = std::round(v);  // plenty of integers too
    const std::string text = format_wire_number(v);
    const double parsed = nlohmann::json::parse(text).get<double>();
    ASSERT_EQ(parsed, core::wire_round(v)) << v << " printed as " << text;
    // C#'s rule: exponent form exactly outside [1e-4, 1e7) after rounding; no trailing zeros.
    const bool exp_form = text.find('E') != std::string::npos;
    const double mag = std::abs(parsed);
    if (mag != 0.0) {
      ASSERT_EQ(exp_form, mag < 1e-4 || mag >= 1e7) << text;
    }
    const std::string mant = text.substr(0, text.find('E'));
    if (mant.find('.') != std::string::npos) {
      ASSERT_NE(mant.back(), '0') << text;
    }
    if (exp_form) {
      ++exponent_forms;
      const std::string e = text.substr(text.find('E') + 1);
      ASSERT_TRUE((e[0] == '+' || e[0] == '-') && e.size() >= 3) << text;
    }
  }
  EXPECT_GT(exponent_forms, 10'000);
}

TEST(ProtocolNumbers, ExactNumbersRoundTripEveryDouble) {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 100'000; ++i) {
    double v = std::bit_cast<double>(rng());
    if (!std::isfinite(v)) continue;
    std::string text;
    append_exact_number(text, v);
    const double back = nlohmann::json::parse(text).get<double>();
    ASSERT_EQ(std::bit_cast<std::uint64_t>(back), std::bit_cast<std::uint64_t>(v)) << text;
  }
  std::string neg_zero;
  append_exact_number(neg_zero, -0.0);
  EXPECT_EQ(neg_zero, "-0.0");
  EXPECT_TRUE(std::signbit(nlohmann::json::parse(neg_zero).get<double>()));
}

// ---- telemetry --------------------------------------------------------------------------

core::Telemetry recorded_snapshot() {
  core::Telemetry t;
  t.ego.position = {909.48, 1128.67};
  t.ego.yaw_rad = 0.0;
  t.ego.speed_mps = 0.0;
  t.ego.s_m = 124.8336;
  t.ego.d_m = 6.164833;
  t.cars.push_back({0, {775.99, 1132.11}, {22.1, -0.3651}, 85.3, 2.012});
  return t;
}

TEST(ProtocolTelemetry, RecordedMessageParsesIntoTheSnapshot) {
  const auto r = parse_telemetry(kRecordedTelemetry);
  ASSERT_TRUE(r.ok()) << r.error();
  ASSERT_TRUE(r.value().has_value());
  EXPECT_EQ(*r.value(), recorded_snapshot());
}

TEST(ProtocolTelemetry, FormatsTheRecordedStateByteForByte) {
  EXPECT_EQ(format_telemetry(recorded_snapshot()), kRecordedTelemetry);
}

TEST(ProtocolTelemetry, KnownStateExactBytesWithExponents) {
  core::Telemetry t;
  t.ego.position = {1000.5, -20.25};
  t.ego.yaw_rad = core::deg_to_rad(90.0);
  t.ego.speed_mps = core::mph_to_mps(49.5);
  t.ego.s_m = 6945.554;
  t.ego.d_m = 1e-5;
  t.previous_path = {{909.48250105225, 1128.6700001}, {12345678.9, 0.000123456789}};
  t.end_path = {0.1, 1e7};
  t.cars.push_back({11, {775.99, 1132.11}, {1e-5, -3.5e-6}, 85.3, 2.012});
  t.cars.push_back({3, {-0.0, 0.0}, {0.0, 0.0}, 0.0, 10.0});
  EXPECT_EQ(
      format_telemetry(t),
      R"(42["telemetry",{"x":1000.5,"y":-20.25,"yaw":90,"speed":49.5,"s":6945.554,"d":1E-05,)"
      R"("previous_path_x":[909.4825,1.234568E+07],"previous_path_y":[1128.67,0.0001234568],)"
      R"("end_path_s":0.1,"end_path_d":1E+07,)"
      R"("sensor_fusion":[[11,775.99,1132.11,1E-05,-3.5E-06,85.3,2.012],[3,0,0,0,0,0,10]]}])");
}

TEST(ProtocolTelemetry, NullForm) {
  const auto r = parse_telemetry(kNullTelemetry);
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_FALSE(r.value().has_value());
}

TEST(ProtocolTelemetry, AcceptsExponentAndIntegerForms) {
  const auto r = parse_telemetry(
      R"(42["telemetry",{"x":1E+07,"y":-3.5E-06,"yaw":359,"speed":2.5E+01,"s":1e-05,"d":6,)"
      R"("previous_path_x":[1E-05,2],"previous_path_y":[-3.5E-06,0.5],"end_path_s":1.5e2,"end_path_d":0,)"
      R"("sensor_fusion":[]}])");
  ASSERT_TRUE(r.ok()) << r.error();
  const core::Telemetry& t = *r.value();
  EXPECT_EQ(t.ego.position.x, 1e7);
  EXPECT_EQ(t.ego.position.y, -3.5e-6);
  EXPECT_EQ(t.ego.yaw_rad, core::deg_to_rad(359.0));
  EXPECT_EQ(t.ego.speed_mps, core::mph_to_mps(25.0));
  EXPECT_EQ(t.ego.s_m, 1e-5);
  EXPECT_EQ(t.previous_path.at(0), (core::Vec2{1e-5, -3.5e-6}));
  EXPECT_EQ(t.end_path.s_m, 150.0);
  EXPECT_TRUE(t.cars.empty());
}

// A formatted telemetry parses back to exactly the wire-rounded snapshot (what the
// in-process loop gives a planner), so wire runs and in-process runs see the same numbers.
TEST(ProtocolTelemetry, FormatThenParseIsWireRounding) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> coord(-5000.0, 5000.0);
  std::uniform_real_distribution<double> yaw(0.0, 2.0 * core::kPi);
  std::uniform_real_distribution<double> speed(0.0, 30.0);
  for (int i = 0; i < 2000; ++i) {
    core::Telemetry t;
    t.ego = {
        {coord(rng), coord(rng)}, yaw(rng), speed(rng), coord(rng) + 5000.0, coord(rng) / 500.0};
    for (int k = 0; k < i % 60; ++k) t.previous_path.push_back({coord(rng), coord(rng)});
    t.end_path = {coord(rng), coord(rng) / 500.0};
    for (int c = 0; c < 12; ++c) {
      t.cars.push_back({c,
                        {coord(rng), coord(rng)},
                        {speed(rng), speed(rng) - 15.0},
                        coord(rng),
                        coord(rng) / 500.0});
    }
    const auto r = parse_telemetry(format_telemetry(t));
    ASSERT_TRUE(r.ok()) << r.error();
    ASSERT_EQ(*r.value(), core::round_like_wire(t));
  }
}

std::string recorded_with(std::string_view from, std::string_view to) {
  std::string s(kRecordedTelemetry);
  const auto at = s.find(from);
  if (at == std::string::npos)
    ADD_FAILURE() << "not in the recorded message: " << from;
  else
    s.replace(at, from.size(), to);
  return s;
}

TEST(ProtocolTelemetry, RejectsBadMessagesWithAReason) {
  const std::string many_points = [] {
    std::string xs;
    for (int i = 0; i < 10'001; ++i) xs += (i ? ",1" : "1");
    return R"("previous_path_x":[)" + xs + R"(],"previous_path_y":[)" + xs + "]";
  }();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"(42["telemetry",{}])", "'x' is missing"},
      {recorded_with(R"("x":909.48)", R"("x":"NaN")"), "'x' is a string (\"NaN\"), not a number"},
      {recorded_with(R"("x":909.48)", R"("x":null)"), "'x' is null, not a number"},
      {recorded_with(R"("x":909.48)", R"("x":NaN)"),
       "not valid JSON (column 21: syntax error while parsing value - invalid literal)"},
      {recorded_with(R"("speed":0)", R"("speed":Infinity)"), "not valid JSON"},
      {recorded_with(R"("speed":0)", R"("speed":1e999)"),
       "not valid JSON (number overflow parsing '1e999')"},
      {recorded_with(R"("s":124.8336)", R"("s":-1e30)"),
       "'s' is out of range: -1e+30 (the limit is 1e+07 either way)"},
      {recorded_with(R"("yaw":0)", R"("yaw":true)"), "'yaw' is a boolean"},
      {recorded_with(R"("d":6.164833,)", ""), "'d' is missing"},
      {recorded_with(R"("previous_path_x":[])", R"("previous_path_x":[1])"),
       "'previous_path_x' has 1 points but 'previous_path_y' has 0"},
      {recorded_with(R"("previous_path_x":[])", R"("previous_path_x":5)"),
       "'previous_path_x' is a number, not an array"},
      {recorded_with(R"("previous_path_x":[],"previous_path_y":[])",
                     R"("previous_path_x":[1,null],"previous_path_y":[1,2])"),
       "'previous_path_x'[1] is null"},
      {recorded_with(R"("previous_path_x":[],"previous_path_y":[])", many_points),
       "more than the limit of 10000"},
      {recorded_with(R"([0,775.99,1132.11,22.1,-0.3651,85.3,2.012])",
                     R"([0,775.99,1132.11,22.1,-0.3651,85.3])"),
       "'sensor_fusion'[0] has 6 values, expected 7"},
      {recorded_with(R"([0,775.99,1132.11,22.1,-0.3651,85.3,2.012])", R"({"id":0})"),
       "'sensor_fusion'[0] is an object"},
      {recorded_with(R"([0,775.99,)", R"([0.5,775.99,)"), "the id is not an integer"},
      {recorded_with(R"(22.1,)", R"("22.1",)"), "'sensor_fusion'[0][3] is a string"},
      {R"(42["telemetry",[1,2]])", "payload is an array, not an object"},
      {recorded_with(
           R"("previous_path_x":[])",
           R"("previous_path_x":)" + std::string(100'000, '[') + std::string(100'000, ']')),
       "deeper than 64 levels"},
      {R"(42["telemetry","hello"])", "payload is a string"},
      {R"(42["telemetry",{"x":909.48,"y":)", "not valid JSON"},
      {R"(42["telemetry"])", "not a [name, payload] array"},
      {R"(42[])", "not a [name, payload] array"},
      {R"(42[5,{}])", "the event name is a number"},
      {R"(42["control",{"next_x":[],"next_y":[]}])", "unexpected event \"control\""},
      {R"(43["telemetry",null])", "does not start with 42"},
      {R"(["telemetry",null])", "does not start with 42"},
      {"", "does not start with 42"},
  };
  for (const auto& [text, reason] : cases) {
    const auto r = parse_telemetry(text);
    ASSERT_FALSE(r.ok()) << text;
    EXPECT_THAT(r.error(), HasSubstr(reason)) << text;
  }
}

TEST(ProtocolTelemetry, ToleratesKeyOrderExtraKeysAndWhitespace) {
  const auto r = parse_telemetry(
      "42[ \"telemetry\" , { \"sensor_fusion\" : [ ] , \"d\" : 6, \"s\" : 1, \"speed\" : 0, "
      "\"yaw\" : 0, "
      "\"y\" : 2, \"x\" : 1, \"previous_path_y\" : [], \"previous_path_x\" : [], \"end_path_d\" : "
      "0, "
      "\"end_path_s\" : 0, \"extra\" : {\"nested\": [1, 2]} } ]");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r.value()->ego.position, (core::Vec2{1.0, 2.0}));
}

// ---- replies ----------------------------------------------------------------------------

TEST(ProtocolControl, RoundTripsDoublesExactly) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> coord(-1e6, 1e6);
  std::vector<core::Vec2> path = {
      {909.48250105225, 1128.6700001}, {-0.0, 0.0}, {1e-300, -2.5e-310}};
  for (int i = 0; i < 500; ++i) path.push_back({coord(rng), coord(rng)});
  const std::string text = format_control(path);
  EXPECT_EQ(text.rfind(R"(42["control",{"next_x":[909.48250105225,-0.0,1e-300,)", 0), 0u)
      << text.substr(0, 80);
  const auto r = parse_reply(text);
  ASSERT_TRUE(r.ok()) << r.error();
  ASSERT_FALSE(r.value().manual);
  ASSERT_EQ(r.value().path.size(), path.size());
  for (std::size_t i = 0; i < path.size(); ++i) {
    EXPECT_EQ(std::bit_cast<std::uint64_t>(r.value().path[i].x),
              std::bit_cast<std::uint64_t>(path[i].x))
        << i;
    EXPECT_EQ(std::bit_cast<std::uint64_t>(r.value().path[i].y),
              std::bit_cast<std::uint64_t>(path[i].y))
        << i;
  }
  EXPECT_EQ(format_control({}), R"(42["control",{"next_x":[],"next_y":[]}])");
}

TEST(ProtocolControl, ReadsRepliesAsTheOriginalDoes) {
  // 15 significant digits, alphabetical keys (what existing planners print); a longer next_y
  // is read only as far as next_x goes.
  const auto r = parse_reply(
      R"(42["control",{"next_x":[909.482501052250,910.1],"next_y":[1128.67000000000,1128.5,1.0]}])");
  ASSERT_TRUE(r.ok()) << r.error();
  ASSERT_EQ(r.value().path.size(), 2u);
  EXPECT_EQ(r.value().path[0], (core::Vec2{909.48250105225, 1128.67}));
  EXPECT_EQ(r.value().path[1], (core::Vec2{910.1, 1128.5}));

  const auto manual = parse_reply(kManual);
  ASSERT_TRUE(manual.ok()) << manual.error();
  EXPECT_TRUE(manual.value().manual);
  EXPECT_TRUE(manual.value().path.empty());
}

TEST(ProtocolControl, RejectsBadRepliesWithAReason) {
  const std::string long_path = [] {
    std::string xs;
    for (int i = 0; i < 10'001; ++i) xs += (i ? ",1" : "1");
    return R"(42["control",{"next_x":[)" + xs + R"(],"next_y":[)" + xs + "]}]";
  }();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"(42["control",{"next_x":[1,2,3],"next_y":[1,2]}])",
       "'next_y' has 2 points, fewer than the 3 of 'next_x'"},
      {R"(42["control",{"next_y":[1]}])", "'next_x' is missing"},
      {R"(42["control",{"next_x":[1]}])", "'next_y' is missing"},
      {R"(42["control",{"next_x":[1,null],"next_y":[1,2]}])", "'next_x'[1] is null, not a number"},
      {R"(42["control",{"next_x":[1,2],"next_y":[1,"NaN"]}])", "'next_y'[1] is a string (\"NaN\")"},
      {R"(42["control",{"next_x":[NaN],"next_y":[1]}])", "not valid JSON"},
      {R"(42["control",{"next_x":[1e39],"next_y":[1]}])",
       "'next_x'[0] is out of range: 1e+39 (the limit is 1e+07 either way)"},
      {R"(42["control",{"next_x":{"0":1},"next_y":[1]}])", "'next_x' is an object, not an array"},
      {R"(42["control",{"next_x":[1],"next_y":7}])", "'next_y' is a number, not an array"},
      {R"(42["control",[1,2]])", "the control payload is an array"},
      {R"(42["control",null])", "the control payload is null"},
      {R"(42["telemetry",{}])", "unexpected event \"telemetry\""},
      {R"(42["control",{"next_x":[1],"next_y":[1]})", "not valid JSON"},
      {R"(["control",{"next_x":[],"next_y":[]}])", "does not start with 42"},
      {long_path, "'next_x' has 10001 points, more than the limit of 10000"},
  };
  for (const auto& [text, reason] : cases) {
    const auto r = parse_reply(text);
    ASSERT_FALSE(r.ok()) << text.substr(0, 100);
    EXPECT_THAT(r.error(), HasSubstr(reason)) << text.substr(0, 100);
  }
}

// ---- framing ----------------------------------------------------------------------------

TEST(ProtocolFraming, PacketsAndEventNames) {
  EXPECT_EQ(split_packet("2").type, PacketType::ping);
  EXPECT_EQ(split_packet("2probe").data, "probe");
  EXPECT_EQ(split_packet("3").type, PacketType::pong);
  EXPECT_EQ(split_packet("41").type, PacketType::message);
  EXPECT_EQ(split_packet("1").type, PacketType::close);
  EXPECT_EQ(split_packet(R"(0{"sid":"x"})").type, PacketType::open);
  EXPECT_EQ(split_packet("").type, PacketType::invalid);
  EXPECT_EQ(split_packet("7").type, PacketType::invalid);
  EXPECT_EQ(split_packet("hello").type, PacketType::invalid);
  EXPECT_TRUE(is_event(kNullTelemetry));
  EXPECT_FALSE(is_event("4"));
  EXPECT_EQ(event_name(kNullTelemetry), "telemetry");
  EXPECT_EQ(event_name(kManual), "manual");
  EXPECT_EQ(event_name(R"(42["telemetry")"), "telemetry");
  EXPECT_EQ(event_name(R"(42["tele)"), std::nullopt);
  EXPECT_EQ(event_name(R"(42[5,{}])"), std::nullopt);
  EXPECT_EQ(event_name(R"(42{})"), std::nullopt);
  EXPECT_EQ(excerpt("a\"b\n"), R"("a\"b\x0a")");
  EXPECT_EQ(excerpt("abcdef", 3), R"("abc"... (6 bytes))");
}

// ---- the original's planners ------------------------------------------------------------

// Every telemetry of a drive, cut and parsed the way the old planners do it, gives the same
// numbers as our parser; the null form is recognised as empty.
TEST(ProtocolOriginalConvention, OurTelemetrySurvivesTheOldHelper) {
  const auto track = testing::default_track();
  sim::World world(track->map, track->line, run::default_config().world,
                   sim::TrafficProfile::faithful, 5);
  testing::OriginalPlannerStats stats;
  for (int cycle = 0; cycle < 1500; ++cycle) {
    const std::string text = format_telemetry(world.telemetry());
    ASSERT_EQ(text.find("null"), std::string::npos);
    const std::string cut = testing::cut_json(text);
    ASSERT_EQ(cut, text.substr(2)) << "the cut must take the whole array";
    const std::string answer = testing::original_planner_answer(text, stats);
    ASSERT_FALSE(answer.empty());
    const auto reply = parse_reply(answer);
    ASSERT_TRUE(reply.ok()) << reply.error();
    world.apply_path(reply.value().path);
    for (int k = 0; k < 1 + cycle % 3; ++k) world.step();
  }
  EXPECT_EQ(stats.full, 1500);
  EXPECT_EQ(stats.unreadable, 0);
  EXPECT_EQ(testing::cut_json(kNullTelemetry), "");
  EXPECT_EQ(testing::original_planner_answer(kNullTelemetry, stats), kManual);
  EXPECT_EQ(stats.empty, 1);
}

}  // namespace
}  // namespace overtake::protocol
