// Map files: every bad-file case gets an error naming the file, the line and the fault; a
// good file parses completely.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "overtake/core/map.hpp"
#include "overtake/core/reference_line.hpp"

namespace overtake::core {
namespace {

using ::testing::HasSubstr;

// Four waypoints of a 400 m square-ish loop, normals pointing outward.
const std::string kGood =
    "0 -100 0 0 -1\n"
    "100 0 141.4214 1 0\n"
    "0 100 282.8427 0 1\n"
    "-100 0 424.2641 -1 0\n";

std::string error_of(const std::string& text) {
  try {
    (void)parse_map(text, "bad.csv");
  } catch (const MapError& e) {
    return e.what();
  }
  return "";
}

TEST(MapParse, GoodFileParsesEveryWaypoint) {
  const Map m = parse_map(kGood, "good.csv");
  ASSERT_EQ(m.waypoints.size(), 4u);
  EXPECT_DOUBLE_EQ(m.waypoints[1].x_m, 100.0);
  EXPECT_DOUBLE_EQ(m.waypoints[3].s_m, 424.2641);
  EXPECT_NEAR(m.loop_length_m, 424.2641 + std::hypot(100.0, 100.0), 1e-9);
  EXPECT_EQ(m.source, "good.csv");
}

TEST(MapParse, BlankLinesCommentsAndCrlfAreAccepted) {
  std::string text = "# a comment\n\n";
  for (char c : kGood) {
    if (c == '\n') text += "\r";
    text += c;
  }
  EXPECT_EQ(parse_map(text, "crlf.csv").waypoints.size(), 4u);
}

TEST(MapErrors, WrongColumnCountNamesTheLine) {
  const std::string e =
      error_of("0 -100 0 0 -1\n100 0 141.4 1\n0 100 282.8 0 1\n-100 0 424.3 -1 0\n");
  EXPECT_THAT(e, HasSubstr("bad.csv:2:"));
  EXPECT_THAT(e, HasSubstr("expected 5 numbers"));
  EXPECT_THAT(e, HasSubstr("found 4"));
}

TEST(MapErrors, NotANumberNamesLineAndColumn) {
  const std::string e =
      error_of("0 -100 0 0 -1\n100 0 141.4 1 0\n0 abc 282.8 0 1\n-100 0 424.3 -1 0\n");
  EXPECT_THAT(e, HasSubstr("bad.csv:3:"));
  EXPECT_THAT(e, HasSubstr("column 2 (y) is not a number: 'abc'"));
}

TEST(MapErrors, TrailingGarbageInANumberIsNotANumber) {
  EXPECT_THAT(error_of("0 -100 0 0 -1\n100 0 141.4x 1 0\n0 100 282.8 0 1\n-100 0 424.3 -1 0\n"),
              HasSubstr("bad.csv:2: column 3 (s) is not a number"));
}

TEST(MapErrors, NanIsRejected) {
  const std::string e =
      error_of("0 -100 0 0 -1\n100 nan 141.4 1 0\n0 100 282.8 0 1\n-100 0 424.3 -1 0\n");
  EXPECT_THAT(e, HasSubstr("bad.csv:2:"));
  EXPECT_THAT(e, HasSubstr("not finite"));
}

TEST(MapErrors, InfinityIsRejected) {
  const std::string e =
      error_of("0 -100 0 0 -1\n100 0 141.4 1 0\n0 100 inf 0 1\n-100 0 424.3 -1 0\n");
  EXPECT_THAT(e, HasSubstr("bad.csv:3:"));
  EXPECT_THAT(e, HasSubstr("column 3 (s) is not finite"));
}

TEST(MapErrors, SNotIncreasingNamesBothLines) {
  const std::string e =
      error_of("0 -100 0 0 -1\n100 0 141.4 1 0\n0 100 141.4 0 1\n-100 0 424.3 -1 0\n");
  EXPECT_THAT(e, HasSubstr("bad.csv:3:"));
  EXPECT_THAT(e, HasSubstr("does not increase"));
  EXPECT_THAT(e, HasSubstr("line 2"));
}

TEST(MapErrors, NormalNotUnitLength) {
  const std::string e =
      error_of("0 -100 0 0 -1\n100 0 141.4 1.02 0\n0 100 282.8 0 1\n-100 0 424.3 -1 0\n");
  EXPECT_THAT(e, HasSubstr("bad.csv:2:"));
  EXPECT_THAT(e, HasSubstr("unit vector"));
}

TEST(MapErrors, NormalWithinOnePercentIsAccepted) {
  EXPECT_EQ(error_of("0 -100 0 0 -1\n100 0 141.4 1.009 0\n0 100 282.8 0 1\n-100 0 424.3 -1 0\n"),
            "");
}

TEST(MapErrors, DuplicatePointNamesBothLines) {
  const std::string e = error_of(
      "0 -100 0 0 -1\n100 0 141.4 1 0\n0 100 282.8 0 1\n100 0 424.3 1 0\n-100 0 624.3 -1 0\n");
  EXPECT_THAT(e, HasSubstr("bad.csv:4:"));
  EXPECT_THAT(e, HasSubstr("duplicates the point on line 2"));
}

TEST(MapErrors, FewerThanFourWaypoints) {
  const std::string e = error_of("0 -100 0 0 -1\n100 0 141.4 1 0\n0 100 282.8 0 1\n");
  EXPECT_THAT(e, HasSubstr("bad.csv"));
  EXPECT_THAT(e, HasSubstr("only 3 waypoints"));
  EXPECT_THAT(e, HasSubstr("at least 4"));
}

TEST(MapErrors, EmptyFile) {
  EXPECT_THAT(error_of(""), HasSubstr("bad.csv: empty map file"));
  EXPECT_THAT(error_of("\n  \n# only a comment\n"), HasSubstr("empty map file"));
}

/// kGood with every x, y and s multiplied by `k`.
std::string scaled(double k) {
  std::string out;
  const double pts[4][5] = {{0, -100, 0, 0, -1},
                            {100, 0, 141.4214, 1, 0},
                            {0, 100, 282.8427, 0, 1},
                            {-100, 0, 424.2641, -1, 0}};
  for (const auto& p : pts) {
    char line[200];
    std::snprintf(line, sizeof line, "%.17g %.17g %.17g %g %g\n", p[0] * k, p[1] * k, p[2] * k,
                  p[3], p[4]);
    out += line;
  }
  return out;
}

TEST(MapLimits, HugeCoordinatesAreRefusedNamingTheLine) {
  // x 1e22 once crashed every command (the reference line's sample count overflowed); 1e4 times
  // a 10 KB map made a run take 826 MB.
  EXPECT_THAT(error_of(scaled(1e20)), HasSubstr("bad.csv:1: y = -1e+22 is out of range"));
  EXPECT_THAT(error_of(scaled(1e4)), HasSubstr("must be within +-100000 m"));
  EXPECT_EQ(error_of(scaled(10.0)), "");  // 4.8 km: fine
}

TEST(MapLimits, TooShortOrTooLongALoopIsRefused) {
  EXPECT_THAT(error_of(scaled(0.1)),
              HasSubstr("the loop is 56.56854562 m long; a map's loop must be 200 to 200000 m"));
  // 95 km by 8 km, every number within range: 206 km around.
  const std::string long_loop =
      "0 0 -99000 0 -1\n95000 0 -4000 1 0\n95000 8000 4000 0 1\n0 8000 99000 -1 0\n";
  EXPECT_THAT(error_of(long_loop),
              HasSubstr("the loop is 206000 m long; a map's loop must be 200 to 200000 m"));
}

TEST(MapLimits, SThatIsNotADistanceAlongTheRoadIsRefused) {
  const std::string text = "0 -100 0 0 -1\n100 0 14142 1 0\n0 100 28284 0 1\n-100 0 42426 -1 0\n";
  EXPECT_THAT(
      error_of(text),
      HasSubstr(
          "bad.csv:2: s grows by 14142 m from line 1, but the waypoints are 141.4213562 m apart"));
}

TEST(MapLimits, ALoopThatCrossesItselfIsRefused) {
  // A bow tie: the divider from the first to the second waypoint crosses the one from the
  // third to the fourth.
  const std::string text =
      "0 0 0 0 -1\n"
      "200 200 282.8427 1 0\n"
      "200 0 482.8427 0 1\n"
      "0 200 765.6854 -1 0\n";
  EXPECT_THAT(
      error_of(text),
      HasSubstr(
          "the road crosses itself: the divider between lines 1-2 crosses it between lines 3-4"));
  EXPECT_EQ(error_of(kGood), "");
}

TEST(MapLimits, TooManyWaypointsAreRefused) {
  std::string text;
  for (int i = 0; i < 20001; ++i) text += std::to_string(i) + " 0 " + std::to_string(i) + " 0 1\n";
  EXPECT_THAT(error_of(text),
              HasSubstr("bad.csv:20001: too many waypoints: a map may have at most 20000"));
}

TEST(MapLimits, AReferenceLineRefusesALoopItCannotSample) {
  // A Map built by hand, not parsed: the line refuses it instead of reading an empty vector.
  Map m = parse_map(kGood, "good.csv");
  m.loop_length_m = 1e30;
  EXPECT_THROW(ReferenceLine line(m), MapError);
  m.loop_length_m = std::nan("");
  EXPECT_THROW(ReferenceLine line(m), MapError);
}

TEST(MapFile, FormatThenParseKeepsTheWaypoints) {
  const Map m = parse_map(kGood, "good.csv");
  const Map again = parse_map(format_map(m.waypoints), "again");
  EXPECT_EQ(again.waypoints, m.waypoints);
}

}  // namespace
}  // namespace overtake::core
