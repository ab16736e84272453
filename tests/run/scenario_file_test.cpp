// Scenario files: what they say becomes the world; bad ones get errors naming the key.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "overtake/core/base64.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "overtake/run/scenario_file.hpp"

namespace overtake::run {

namespace {

using nlohmann::json;
using ::testing::HasSubstr;

std::string error_of(const std::string& text) {
  try {
    (void)parse_scenario(json::parse(text), "s.json", core::RoadParams{});
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(ScenarioFile, ParsesEveryPart) {
  const auto sc = parse_scenario(json::parse(R"({
    "name": "x", "duration_s": 12,
    "ego": {"s_m": 300, "lane": 2, "speed_mps": 20},
    "cars": [{"gap_m": 25, "lane": 0, "speed_mps": 15}, {"s_m": 10, "lane": 1, "speed_mps": 0}],
    "events": [{"t_s": 3, "car": 1, "speed_mps": 10, "accel_mps2": 2},
               {"t_s": 1, "car": 0, "change_lane": 1},
               {"t_s": 2, "car": 0, "brake_mps2": 6, "duration_s": 1.5}]})"),
                                 "s.json", core::RoadParams{});
  EXPECT_EQ(sc.name, "x");
  EXPECT_EQ(*sc.duration_s, 12.0);
  EXPECT_EQ(sc.ego_s_m, 300.0);
  EXPECT_EQ(sc.ego_d_m, 10.0);
  ASSERT_EQ(sc.cars.size(), 2u);
  EXPECT_EQ(sc.cars[0].s_m, 325.0);  // gap from the ego
  EXPECT_EQ(sc.cars[1].s_m, 10.0);
  ASSERT_EQ(sc.events.size(), 3u);  // sorted by time
  EXPECT_EQ(sc.events[0].action, sim::ScenarioAction::change_lane);
  EXPECT_EQ(sc.events[1].action, sim::ScenarioAction::brake);
  EXPECT_EQ(sc.events[1].duration_s, 1.5);
  EXPECT_EQ(sc.events[2].action, sim::ScenarioAction::set_speed);
}

TEST(ScenarioFile, ErrorsNameTheKey) {
  EXPECT_THAT(error_of(R"({"cars": [{"lane": 0, "speed_mps": 15}]})"),
              HasSubstr("scenario.cars[0]: give exactly one of gap_m"));
  EXPECT_THAT(error_of(R"({"cars": [{"gap_m": 5, "lane": 7, "speed_mps": 15}]})"),
              HasSubstr("scenario.cars[0].lane: 7 is out of range (0 to 2)"));
  EXPECT_THAT(error_of(R"({"cars": [{"gap_m": 5, "lane": 0}]})"),
              HasSubstr("scenario.cars[0].speed_mps: missing"));
  EXPECT_THAT(error_of(R"({"ego": {"speed_mps": "fast"}})"),
              HasSubstr("scenario.ego.speed_mps: expected a finite number"));
  EXPECT_THAT(error_of(R"({"events": [{"t_s": 1, "car": 0, "change_lane": 1}]})"),
              HasSubstr("car 0 is not one of the scenario's 0 cars"));
  EXPECT_THAT(error_of(R"({"cars": [{"gap_m": 5, "lane": 0, "speed_mps": 1}],
                           "events": [{"t_s": 1, "car": 0, "brake_mps2": 6}]})"),
              HasSubstr("scenario.events[0].duration_s: missing"));
  EXPECT_THAT(error_of(R"({"cars": [{"gap_m": 5, "lane": 0, "speed_mps": 1}],
                           "events": [{"t_s": 1, "car": 0}]})"),
              HasSubstr("give exactly one of change_lane"));
  EXPECT_THAT(error_of(R"({"speed": 3})"), HasSubstr("scenario.speed: unknown key"));
  EXPECT_THAT(error_of(R"({"duration_s": -1})"),
              HasSubstr("scenario.duration_s: -1 is out of range (0 to 604800)"));
  EXPECT_THAT(error_of(R"({"duration_s": 0})"),
              HasSubstr("scenario.duration_s: must be more than 0"));
  EXPECT_THAT(error_of(R"([])"), HasSubstr("scenario: expected an object"));
}

TEST(ScenarioFile, NumbersAreBoundedNotWrappedOrSaturated) {
  // 2^32 + 1 once became lane 1; 1e300 m/s gave a report with a NaN distance.
  EXPECT_THAT(error_of(R"({"cars": [{"gap_m": 5, "lane": 4294967297, "speed_mps": 15}]})"),
              HasSubstr("scenario.cars[0].lane: 4294967297 is out of range (0 to 2)"));
  EXPECT_THAT(error_of(R"({"cars": [{"gap_m": 5, "lane": -4294967295, "speed_mps": 15}]})"),
              HasSubstr("scenario.cars[0].lane: -4294967295 is out of range (0 to 2)"));
  EXPECT_THAT(error_of(R"({"cars": [{"gap_m": 5, "lane": 1, "speed_mps": 1e300}]})"),
              HasSubstr("scenario.cars[0].speed_mps: 1e+300 is out of range (0 to 100)"));
  EXPECT_THAT(error_of(R"({"ego": {"speed_mps": 1000000}})"),
              HasSubstr("scenario.ego.speed_mps: 1000000 is out of range (0 to 100)"));
  EXPECT_THAT(error_of(R"({"ego": {"s_m": 1e12}})"),
              HasSubstr("scenario.ego.s_m: 1000000000000.0 is out of range"));
  EXPECT_THAT(error_of(R"({"cars": [{"gap_m": 5, "lane": 1, "speed_mps": 1}],
                           "events": [{"t_s": 1, "car": 18446744073709551617, "change_lane": 0}]})"),
              HasSubstr("scenario.events[0].car"));
  // A scenario longer than a week is the scenario's fault, not --minutes'.
  EXPECT_THAT(error_of(R"({"duration_s": 1e9})"),
              HasSubstr("scenario.duration_s: 1000000000.0 is out of range (0 to 604800)"));
}

// The largest values a scenario may hold still give a report of finite numbers (1e300 m/s
// once gave a NaN distance, written as null in the JSON).
TEST(ScenarioFile, TheLargestAcceptedValuesGiveAFiniteReport) {
  const auto path = std::filesystem::temp_directory_path() / "overtake_scenario_bounds.json";
  {
    std::ofstream f(path);
    f << R"({"duration_s": 20, "ego": {"s_m": 100000, "lane": 2, "speed_mps": 100},
             "cars": [{"gap_m": 100000, "lane": 0, "speed_mps": 100},
                      {"gap_m": -100000, "lane": 2, "speed_mps": 100}],
             "events": [{"t_s": 1, "car": 0, "speed_mps": 100, "accel_mps2": 50}]})";
  }
  DriveOptions o;
  o.scenario = path;
  o.minutes_from_scenario = true;
  o.policy = "walkthrough";
  const DriveResult r = drive(o);
  std::filesystem::remove(path);
  json report = report_to_json(r.report, r.provenance);
  // The nulls of a whole run: no early end, and no reason to leave normal planning.
  EXPECT_TRUE(report["ended_early"].is_null());
  EXPECT_TRUE(report["plan_status"]["first_reason"].is_null());
  report.erase("ended_early");
  report["plan_status"].erase("first_reason");
  // ... and near-miss figures that were never measured (no car ever ahead in the lane).
  for (const char* key : {"min_ttc_ahead_s", "min_ttc_entering_s", "min_time_headway_s"}) {
    EXPECT_TRUE(report["safety"][key].is_null() || report["safety"][key].is_number()) << key;
    report["safety"].erase(key);
  }
  const std::string text = report.dump();
  EXPECT_EQ(text.find("null"), std::string::npos) << text;  // a NaN is written as null
  EXPECT_TRUE(std::isfinite(r.report.distance_m));
  EXPECT_GT(r.report.distance_m, 0.0);
}

// Found by fuzz/scenario_fuzz.cpp: a number beyond a double escaped the file's reader as a
// bare JSON library exception instead of an error naming the file.
TEST(ScenarioFile, ANumberBeyondADoubleIsBadJsonNamingTheFile) {
  try {
    (void)parse_scenario_text(R"({"ego": {"s_m": 1e999}})", "huge.json", core::RoadParams{});
    FAIL() << "accepted";
  } catch (const ConfigError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("huge.json: not valid JSON"));
  } catch (const std::exception& e) {
    FAIL() << "not a ConfigError: " << e.what();
  }
}

// A lead-in as long as the scenario left nothing to judge, and the scenario passed even with
// an at-fault collision: refused when the file is read, naming the file and both values.
TEST(ScenarioFile, ALeadInAsLongAsTheScenarioIsRefused) {
  const std::string checkpoint = pack_blob("bytes");
  const auto cut_with = [&](const std::string& duration, const std::string& lead_in) {
    return R"({"duration_s": )" + duration + R"(, "cut": {"traffic": "reactive", "start_s": 1,
               "at_s": 2, "lead_in_s": )" +
           lead_in + R"(, "checkpoint": ")" + checkpoint + R"("}})";
  };
  const std::string error = error_of(cut_with("20", "20"));
  EXPECT_THAT(error, HasSubstr("s.json: invalid scenario"));
  EXPECT_THAT(error, HasSubstr("scenario.cut.lead_in_s: 20 s is not less than "
                               "scenario.duration_s (20 s): nothing after the lead-in"));
  EXPECT_THAT(error_of(cut_with("20", "35.5")), HasSubstr("35.5 s is not less than"));
  EXPECT_EQ(error_of(cut_with("20", "19.5")), "");
  EXPECT_EQ(error_of(cut_with("20", "0")), "");
}

// 20,000 cars in a 2 s scenario took 37 s to drive: the cars and events of a scripted scenario
// are counted where they enter, and the error names the key, the count and the limit.
TEST(ScenarioFile, CarsAndEventsAreBoundedWhereTheyEnter) {
  const auto with = [](std::size_t cars, std::size_t events) {
    json j = {{"duration_s", 2}, {"cars", json::array()}, {"events", json::array()}};
    for (std::size_t i = 0; i < cars; ++i) {
      j["cars"].push_back({{"s_m", static_cast<double>(i)}, {"lane", 0}, {"speed_mps", 10}});
    }
    for (std::size_t i = 0; i < events; ++i) {
      j["events"].push_back({{"t_s", 1}, {"car", 0}, {"speed_mps", 12}, {"accel_mps2", 1}});
    }
    return j.dump();
  };
  EXPECT_THAT(error_of(with(20000, 0)),
              HasSubstr("scenario.cars: 20000 cars, more than the 64 a scenario may place"));
  EXPECT_THAT(error_of(with(65, 0)), HasSubstr("scenario.cars: 65 cars, more than the 64"));
  EXPECT_EQ(error_of(with(64, 0)), "");
  EXPECT_THAT(error_of(with(1, 200000)),
              HasSubstr("scenario.events: 200000 events, more than the 10000 a scenario may hold"));
  EXPECT_THAT(error_of(with(1, 10001)), HasSubstr("scenario.events: 10001 events"));
  const auto sc = parse_scenario(json::parse(with(64, 10000)), "s.json", core::RoadParams{});
  EXPECT_EQ(sc.cars.size(), 64U);
  EXPECT_EQ(sc.events.size(), 10000U);
}

std::string blob_error(const std::string& text) {
  try {
    (void)unpack_blob(text, "scenario.cut.checkpoint");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

// A blob of a few KB could inflate to 256 MB (two in a 2.7 MB file: 540 MB; eight under
// --jobs 8: 4.3 GB); the bound is now 16 MB, named in the error.
TEST(ScenarioBlob, InflatesToSixteenMegabytesAtMost) {
  const std::string at_limit(kMaxBlobBytes, '\0');
  EXPECT_EQ(unpack_blob(pack_blob(at_limit), "x").size(), kMaxBlobBytes);
  const std::string bomb = pack_blob(std::string(kMaxBlobBytes + 1, '\0'));
  EXPECT_LT(bomb.size(), 40000U);
  EXPECT_THAT(blob_error(bomb), HasSubstr("scenario.cut.checkpoint: more than 16 MB once "
                                          "inflated"));
}

// Garbage after a checkpoint's zlib stream was accepted.
TEST(ScenarioBlob, BytesAfterTheZlibStreamAreRefused) {
  const std::string packed = *core::base64_decode(pack_blob("a checkpoint's bytes"));
  EXPECT_EQ(unpack_blob(core::base64_encode(packed), "x"), "a checkpoint's bytes");
  EXPECT_THAT(blob_error(core::base64_encode(packed + "xyz")),
              HasSubstr("scenario.cut.checkpoint: 3 bytes after the end of the zlib stream"));
  EXPECT_THAT(blob_error(core::base64_encode(packed + packed)),
              HasSubstr(std::to_string(packed.size()) + " bytes after the end"));
  // Cut short, it is damaged as before.
  EXPECT_THAT(blob_error(core::base64_encode(packed.substr(0, packed.size() - 2))),
              HasSubstr("damaged or truncated"));
}

TEST(ScenarioFile, TheShippedExampleDrives) {
  DriveOptions o;
  o.scenario = std::string(OVERTAKE_SOURCE_DIR) + "/data/scenarios/scripted-cut-in.json";
  o.minutes_from_scenario = true;
  o.policy = "walkthrough";
  const DriveResult r = drive(o);
  EXPECT_DOUBLE_EQ(r.report.duration_s, 30.0);
  EXPECT_EQ(r.provenance.traffic, "scripted");
  EXPECT_EQ(r.provenance.scenario, "cut-in 20 m ahead");
  EXPECT_EQ(report_to_json(r.report, r.provenance)["config"]["scenario"], "cut-in 20 m ahead");
}

}  // namespace
}  // namespace overtake::run
