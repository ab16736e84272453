// The shipped config file equals the structs' defaults, and bad config gets errors that
// name the key.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "overtake/planner/policy.hpp"
#include "overtake/planner/reference/assertiveness.hpp"
#include "overtake/replay/replay.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/sim/run.hpp"
#include "overtake/sim/world.hpp"

namespace overtake::run {

namespace {

using nlohmann::json;
using ::testing::HasSubstr;

json shipped() {
  std::ifstream in(std::string(OVERTAKE_SOURCE_DIR) + "/config/overtake.json");
  std::stringstream buf;
  buf << in.rdbuf();
  return json::parse(buf.str());
}

std::string error_of(const json& j) {
  try {
    (void)apply_config_json(Config{}, j, "user.json");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(ConfigDefaults, ShippedFileHoldsExactlyTheStructDefaults) {
  EXPECT_EQ(config_to_json(Config{}), shipped())
      << "config/overtake.json is out of step with the params structs; regenerate it with "
         "`overtake config --defaults > config/overtake.json`";
  EXPECT_EQ(apply_config_json(Config{}, shipped(), "shipped"), Config{});
  EXPECT_EQ(default_config(), Config{});
}

// planner.reference.assertiveness: one knob that moves the soft costs, margins and gaps from
// the shipped defaults (0) to the edge (1) together; a key set by hand in the same file wins.
TEST(ConfigAssertiveness, TheKnobMovesItsKeysTogetherAndAKeySetByHandWins) {
  const planner::ReferenceParams d = Config{}.planner.reference;
  const auto at = [](const std::string& text) {
    return apply_config_json(Config{}, json::parse(text), "user.json").planner.reference;
  };
  EXPECT_EQ(at(R"({"planner": {"reference": {"assertiveness": 0}}})"), d);
  const planner::ReferenceParams half = at(R"({"planner": {"reference": {"assertiveness": 0.5}}})");
  EXPECT_DOUBLE_EQ(half.assertiveness, 0.5);
  EXPECT_DOUBLE_EQ(half.trajectory.proximity_weight, d.trajectory.proximity_weight * 0.25);
  EXPECT_DOUBLE_EQ(half.trajectory.rear_weight, d.trajectory.rear_weight * 0.25);
  EXPECT_DOUBLE_EQ(half.trajectory.lon_margin_m, (d.trajectory.lon_margin_m + 0.2) / 2);
  EXPECT_DOUBLE_EQ(half.behaviour.min_gap_m, (d.behaviour.min_gap_m + 1.0) / 2);
  EXPECT_DOUBLE_EQ(half.behaviour.lead_brake_mps2, (d.behaviour.lead_brake_mps2 + 9.0) / 2);
  EXPECT_EQ(half.prediction, d.prediction);  // nothing else moves
  EXPECT_EQ(half.behaviour.cruise_speed_mps, d.behaviour.cruise_speed_mps);
  // The car's own pace does not move before 0.75.
  const planner::ReferenceParams three_quarters =
      at(R"({"planner": {"reference": {"assertiveness": 0.75}}})");
  EXPECT_DOUBLE_EQ(three_quarters.behaviour.min_gap_m,
                   d.behaviour.min_gap_m + (1.0 - d.behaviour.min_gap_m) * 0.75);
  EXPECT_EQ(three_quarters.trajectory.max_accel_mps2, d.trajectory.max_accel_mps2);
  EXPECT_EQ(three_quarters.behaviour.passing_speed_mps, d.behaviour.passing_speed_mps);
  // At 1 the pace is at its edge and the margins at 0.85 of their way.
  const planner::ReferenceParams edge = at(R"({"planner": {"reference": {"assertiveness": 1}}})");
  EXPECT_EQ(edge, planner::with_assertiveness(d, 1.0));
  EXPECT_DOUBLE_EQ(edge.trajectory.proximity_weight, d.trajectory.proximity_weight * 0.15 * 0.15);
  EXPECT_DOUBLE_EQ(edge.trajectory.lat_margin_m,
                   d.trajectory.lat_margin_m + (0.1 - d.trajectory.lat_margin_m) * 0.85);
  EXPECT_DOUBLE_EQ(
      edge.behaviour.follower_brake_mps2,
      d.behaviour.follower_brake_mps2 + (9.0 - d.behaviour.follower_brake_mps2) * 0.85);
  EXPECT_DOUBLE_EQ(edge.trajectory.max_accel_mps2, 8.5);
  EXPECT_DOUBLE_EQ(edge.trajectory.max_jerk_mps3, 9.0);
  EXPECT_DOUBLE_EQ(edge.behaviour.passing_speed_mps, 12.0);
  EXPECT_DOUBLE_EQ(edge.behaviour.hysteresis, 0.0);
  // Every key moves one way only, from the default towards its edge, never past it.
  EXPECT_EQ(planner::assertiveness_keys().size(), 16U);
  for (const planner::AssertivenessKey& k : planner::assertiveness_keys()) {
    planner::ReferenceParams at0 = d;
    const double v0 = k.field(at0);
    double last = v0;
    for (int i = 1; i <= 20; ++i) {
      planner::ReferenceParams p = planner::with_assertiveness(d, i / 20.0);
      const double v = k.field(p);
      EXPECT_LE(std::abs(v - k.edge), std::abs(last - k.edge) + 1e-12)
          << k.key << " at " << i / 20.0;
      EXPECT_LE(std::abs(v - v0), std::abs(k.edge - v0) + 1e-12) << k.key;
      last = v;
    }
    EXPECT_NE(last, v0) << k.key << " does not move";
    // Its name is the config key of its field: set by hand at 1, the field keeps that value.
    const auto dot = k.key.find('.');
    const json by_hand = {{"planner",
                           {{"reference",
                             {{"assertiveness", 1.0},
                              {k.key.substr(0, dot), {{k.key.substr(dot + 1), v0 * 0.5}}}}}}}};
    planner::ReferenceParams set = at(by_hand.dump());
    EXPECT_DOUBLE_EQ(k.field(set), v0 * 0.5) << k.key;
  }
  // A key set by hand keeps its value; the others move.
  const planner::ReferenceParams mixed =
      at(R"({"planner": {"reference": {"assertiveness": 0.5, "behaviour": {"min_gap_m": 3.5}}}})");
  EXPECT_DOUBLE_EQ(mixed.behaviour.min_gap_m, 3.5);
  EXPECT_DOUBLE_EQ(mixed.trajectory.lon_margin_m, half.trajectory.lon_margin_m);
  // The config it gives reads back as itself (the knob is not applied twice).
  const Config c = apply_config_json(
      Config{}, json::parse(R"({"planner": {"reference": {"assertiveness": 0.5}}})"), "u");
  EXPECT_EQ(apply_config_json(Config{}, config_to_json(c), "again"), c);
  // Outside 0..1 it is refused, naming the key.
  EXPECT_THAT(error_of(json::parse(R"({"planner": {"reference": {"assertiveness": 1.5}}})")),
              HasSubstr("planner.reference.assertiveness"));
  EXPECT_THAT(error_of(json::parse(R"({"planner": {"reference": {"assertiveness": "high"}}})")),
              HasSubstr("planner.reference.assertiveness"));
}

TEST(ConfigOverrides, ASubsetOfKeysOverridesOnlyThose) {
  const Config c = apply_config_json(
      Config{},
      json::parse(R"({"world": {"traffic": {"car_count": 5, "calm": {"politeness": 0.1}}}})"),
      "user.json");
  EXPECT_EQ(c.world.traffic.car_count, 5);
  EXPECT_DOUBLE_EQ(c.world.traffic.calm.politeness, 0.1);
  EXPECT_EQ(c.world.referee, Config{}.world.referee);
}

TEST(ConfigOverrides, RoadIsSharedByWorldAndPlanner) {
  const Config c =
      apply_config_json(Config{}, json::parse(R"({"road": {"lane_width_m": 3.7}})"), "u");
  EXPECT_DOUBLE_EQ(c.world.road.lane_width_m, 3.7);
  EXPECT_DOUBLE_EQ(c.planner.road.lane_width_m, 3.7);
}

// The step is one key, the world's: every policy spaces its points by it. Each policy drives
// an empty road for a minute; at its steady speed, the newest points of its last path (the
// end of the queue the world still holds) are that speed times the step apart.
TEST(ConfigStep, EveryPolicySpacesItsPointsForTheWorldsStep) {
  const auto track = load_track(std::nullopt);
  for (const double step_s : {0.04, 0.02}) {
    const json j = {{"world", {{"step_s", step_s}, {"traffic", {{"car_count", 0}}}}}};
    const Config c = apply_config_json(Config{}, j, "step.json");
    EXPECT_DOUBLE_EQ(c.planner.step_s, step_s);
    for (const auto& info : planner::list_policies()) {
      SCOPED_TRACE(info.name + " at a step of " + std::to_string(step_s) + " s");
      sim::World world(track->map, track->line, c.world, sim::TrafficProfile::faithful, 1);
      auto policy = planner::make_policy(info.name, track->line, c.planner);
      ASSERT_TRUE(policy);
      sim::RunOptions opts;
      opts.duration_s = 60.0;
      (void)sim::run_drive(
          world, [&](const core::Telemetry& t) { return policy->plan(t); }, opts);
      const double speed_mps = world.ego().speed_mps;
      ASSERT_GT(speed_mps, 20.0);  // cruising
      const std::vector<core::Vec2> queue = world.telemetry().previous_path;
      ASSERT_GE(queue.size(), 11u);
      for (std::size_t i = queue.size() - 10; i < queue.size(); ++i) {
        const double gap_s = core::distance(queue[i], queue[i - 1]) / speed_mps;
        EXPECT_NEAR(gap_s, step_s, 0.1 * step_s) << "point " << i;
      }
    }
  }
}

TEST(ConfigErrors, ThePlannersStepKeysAreGoneForTheWorlds) {
  EXPECT_THAT(error_of(json::parse(R"({"planner": {"walkthrough": {"step_s": 0.04}}})")),
              HasSubstr("unknown key 'planner.walkthrough.step_s'"));
  EXPECT_THAT(
      error_of(json::parse(R"({"planner": {"reference": {"trajectory": {"step_s": 0.04}}}})")),
      HasSubstr("unknown key 'planner.reference.trajectory.step_s'"));
  EXPECT_THAT(error_of(json::parse(R"({"planner": {"step_s": 0.04}})")),
              HasSubstr("unknown key 'planner.step_s'"));
}

TEST(ConfigOverrides, TheCarFootprintIsOneSectionForEveryBody) {
  const Config c = apply_config_json(
      Config{}, json::parse(R"({"car": {"length_m": 5.2, "width_m": 2.1}})"), "u");
  EXPECT_EQ(c.world.car, c.car);
  EXPECT_EQ(c.planner.car, c.car);
  EXPECT_DOUBLE_EQ(c.world.car.length_m, 5.2);
  EXPECT_DOUBLE_EQ(c.planner.car.width_m, 2.1);
  const auto track = load_track(std::nullopt);
  const replay::ReplayHeader h = replay::make_replay_header(track->line, c.world, {});
  EXPECT_DOUBLE_EQ(h.car_length_m, 5.2);
  EXPECT_DOUBLE_EQ(h.car_width_m, 2.1);
  for (const char* old :
       {R"({"world": {"ego": {"length_m": 5}}})", R"({"world": {"traffic": {"car_width_m": 2}}})",
        R"({"planner": {"reference": {"car_length_m": 5}}})"}) {
    EXPECT_THAT(error_of(json::parse(old)), HasSubstr("unknown key")) << old;
  }
  EXPECT_THAT(error_of(json::parse(R"({"car": {"width_m": 0.1}})")),
              HasSubstr("car.width_m must be between 0.5 and 20 (got 0.1)"));
}

TEST(ConfigErrors, UnknownKeyIsNamedWithItsPath) {
  const std::string e = error_of(json::parse(R"({"world": {"traffic": {"car_cuont": 5}}})"));
  EXPECT_THAT(e, HasSubstr("user.json"));
  EXPECT_THAT(e, HasSubstr("unknown key 'world.traffic.car_cuont'"));
}

TEST(ConfigErrors, WrongTypeIsNamed) {
  EXPECT_THAT(error_of(json::parse(R"({"world": {"step_s": "fast"}})")),
              HasSubstr("world.step_s: expected a number, got a string"));
  EXPECT_THAT(error_of(json::parse(R"({"world": {"traffic": {"car_count": 2.5}}})")),
              HasSubstr("world.traffic.car_count: expected an integer"));
  EXPECT_THAT(error_of(json::parse(R"({"world": {"wire_rounding": 1}})")),
              HasSubstr("world.wire_rounding: expected true or false"));
  EXPECT_THAT(error_of(json::parse(R"({"world": []})")), HasSubstr("world: expected an object"));
  EXPECT_THAT(error_of(json::parse(R"([1, 2])")), HasSubstr("top level must be a JSON object"));
}

TEST(ConfigErrors, InvalidValuesAreNamedWithTheValue) {
  const std::string e = error_of(
      json::parse(R"({"world": {"traffic": {"car_count": -1}, "referee": {"max_jerk_mps3": 0}}})"));
  EXPECT_THAT(e, HasSubstr("world.traffic.car_count must be between 0 and 64 (got -1)"));
  EXPECT_THAT(e, HasSubstr("world.referee.max_jerk_mps3 must be a positive number (got 0)"));
  EXPECT_THAT(
      error_of(json::parse(R"({"world": {"min_steps_per_call": 3, "max_steps_per_call": 2}})")),
      HasSubstr("world.min_steps_per_call (3) must not exceed world.max_steps_per_call (2)"));
  EXPECT_THAT(
      error_of(json::parse(R"({"planner": {"walkthrough": {"anchor_distances_m": [30, 20]}}})")),
      HasSubstr("planner.walkthrough.anchor_distances_m must be positive and increasing"));
}

TEST(ConfigErrors, AbsurdValuesAreRefusedWithTheirBounds) {
  // A step of 1e308 s ran no step; 1e-9 s never ended.
  EXPECT_THAT(error_of(json::parse(R"({"world": {"step_s": 1e308}})")),
              HasSubstr("world.step_s must be between 0.001 and 0.5 (got 1e+308)"));
  EXPECT_THAT(error_of(json::parse(R"({"world": {"step_s": 1e-9}})")),
              HasSubstr("world.step_s must be between 0.001 and 0.5 (got 1e-09)"));
  EXPECT_THAT(error_of(json::parse(R"({"road": {"lane_width_m": 1e9}})")),
              HasSubstr("road.lane_width_m must be between 1 and 20"));
}

TEST(ConfigErrors, AKeyGivenTwiceIsRefused) {
  try {
    (void)apply_config_text(
        Config{}, R"({"world": {"step_s": 0.02, "traffic": {}, "step_s": 0.05}})", "twice.json");
    FAIL() << "a duplicated key was accepted";
  } catch (const ConfigError& e) {
    EXPECT_THAT(std::string(e.what()),
                HasSubstr("twice.json: the key 'world.step_s' is given twice"));
  }
  try {
    (void)apply_config_text(Config{}, R"({"road": {}, "road": {}})", "twice.json");
    FAIL() << "a duplicated key was accepted";
  } catch (const ConfigError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("the key 'road' is given twice"));
  }
  // The same key in different objects is fine.
  EXPECT_NO_THROW((void)apply_config_text(
      Config{}, R"({"world": {"traffic": {"car_count": 3}}, "planner": {}})", "ok.json"));
}

TEST(ConfigErrors, MissingAndMalformedFilesAreNamed) {
  try {
    (void)load_config(std::filesystem::path("/nonexistent/cfg.json"));
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("/nonexistent/cfg.json"));
  }
  const auto path = std::filesystem::temp_directory_path() / "overtake_bad_config.json";
  {
    std::ofstream out(path);
    out << "{\"world\": ";
  }
  try {
    (void)load_config(path);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("not valid JSON"));
  }
  std::filesystem::remove(path);
}

// Found by fuzz/config_fuzz.cpp: the JSON library reports a number beyond a double as
// out_of_range, not as a parse error, and it escaped as a bare library exception that named
// neither the file nor the fault's place.
TEST(ConfigErrors, ANumberBeyondADoubleIsBadJsonNamingTheFile) {
  for (const char* text :
       {R"({"road": {"lane_width_m": 1e999}})", R"({"world": {"step_s": -1e400}})"}) {
    try {
      (void)apply_config_text(Config{}, text, "huge.json");
      ADD_FAILURE() << "accepted " << text;
    } catch (const ConfigError& e) {
      EXPECT_THAT(std::string(e.what()), HasSubstr("huge.json: not valid JSON"));
      EXPECT_THAT(std::string(e.what()), HasSubstr("number overflow"));
    } catch (const std::exception& e) {
      ADD_FAILURE() << "not a ConfigError: " << e.what();
    }
  }
}

TEST(ConfigHash, ChangesWithAnyValue) {
  Config c;
  const std::string h = config_hash(c);
  c.world.traffic.calm.politeness += 0.01;
  EXPECT_NE(config_hash(c), h);
  EXPECT_EQ(config_hash(Config{}), h);
}

}  // namespace
}  // namespace overtake::run
