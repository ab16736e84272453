// From a failure to a regression test: replays carry checkpoints, `cut` makes a scenario of a
// moment, driving it with the same planner reproduces the failure at the same moment (reactive
// and replayed traffic), the library's scenarios reproduce the failures they were cut from,
// and bad input is refused naming what is wrong.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/replay/replay.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "overtake/run/scenario_file.hpp"
#include "overtake/scenarios/cut.hpp"
#include "overtake/sim/checkpoint.hpp"
#include "temp_dir.hpp"

namespace overtake::batch {

using base::fixed_text;
using base::read_file;
using base::UsageError;
using run::ConfigError;
using run::drive;
using run::DriveOptions;
using run::DriveResult;
using run::load_scenario;
using run::pack_blob;
using run::parse_scenario;
using run::read_json_file;
using scenarios::cut_replay;
using scenarios::CutOptions;
using scenarios::CutResult;
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using ::testing::HasSubstr;

class TempDir : public test::TempDir {
 public:
  TempDir() : test::TempDir("overtake-cut") {}
};

/// Collisions of a report as (time, kind).
std::vector<std::pair<double, std::string>> collisions_of(const sim::RunReport& r) {
  std::vector<std::pair<double, std::string>> out;
  for (const sim::Incident& i : r.incidents) {
    if (i.type != sim::IncidentType::collision) continue;
    out.emplace_back(i.t_s, i.collision ? std::string(sim::to_string(i.collision->kind)) : "");
  }
  return out;
}

DriveResult drive_scenario(const fs::path& scenario, const std::string& policy) {
  DriveOptions o;
  o.scenario = scenario;
  o.minutes_from_scenario = true;
  o.policy = policy;
  return drive(o);
}

/// seed001 on the built-in track, faithful traffic, seed 2: it changes lanes into a car at
/// t 79.36 s (found by `overtake hunt`).
struct Recorded {
  TempDir dir;
  fs::path replay;
  sim::RunReport report;
};

const Recorded& seed001_run() {
  static Recorded* r = [] {
    auto* rec = new Recorded;
    rec->replay = rec->dir.path() / "run.otr";
    DriveOptions o;
    o.policy = "seed001";
    o.seed = 2;
    o.minutes = 1.5;
    o.record = rec->replay;
    rec->report = drive(o).report;
    return rec;
  }();
  return *r;
}

constexpr double kCollisionS = 79.36;

TEST(Checkpoints, ARecordedReplayCarriesThemEveryTenSeconds) {
  const replay::Replay r = replay::read_replay(seed001_run().replay);
  ASSERT_EQ(r.checkpoints.size(), 9U);  // t 0, 10, ..., 80 s (the run ends at 90 s)
  for (std::size_t i = 0; i < r.checkpoints.size(); ++i) {
    const sim::Checkpoint c = sim::decode_checkpoint(r.checkpoints[i].bytes, "test");
    EXPECT_NEAR(c.info.t_s, 10.0 * static_cast<double>(i), 0.061);  // at a cycle's start
    EXPECT_EQ(c.info.policy, "seed001");
    EXPECT_EQ(c.info.traffic, "faithful");
    EXPECT_EQ(c.info.seed, 2U);
    EXPECT_FALSE(c.planner.empty());  // a built-in policy's state
  }
}

TEST(Cut, ReactiveAndReplayedScenariosReproduceTheCollisionAtTheSameMoment) {
  const Recorded& run = seed001_run();
  const auto original = collisions_of(run.report);
  ASSERT_FALSE(original.empty());
  ASSERT_NEAR(original.front().first, kCollisionS, 1e-9);
  TempDir dir;
  for (const bool replayed : {false, true}) {
    CutOptions o;
    o.replay = run.replay;
    o.at_s = kCollisionS;
    o.replayed = replayed;
    o.out = dir.path() / (replayed ? "replayed.json" : "reactive.json");
    const CutResult cut = cut_replay(o);
    EXPECT_TRUE(cut.exact_start);
    EXPECT_NEAR(cut.start_s, kCollisionS - 15.0, 0.061);  // the first cycle at or after it
    EXPECT_NEAR(cut.end_s, kCollisionS + 5.0, 1e-9);
    EXPECT_EQ(cut.planner_state, "restored");
    EXPECT_THAT(cut.incident, HasSubstr("collision ego_lane_change (at fault) at t 79.36 s"));

    const DriveResult again = drive_scenario(o.out, "seed001");
    const auto got = collisions_of(again.report);
    ASSERT_FALSE(got.empty()) << (replayed ? "replayed" : "reactive");
    EXPECT_DOUBLE_EQ(got.front().first, original.front().first);
    EXPECT_EQ(got.front().second, original.front().second);
    EXPECT_EQ(again.provenance.traffic, replayed ? "replayed" : "reactive");
    EXPECT_NEAR(again.report.duration_s, cut.end_s - cut.start_s, 1e-6);
  }
}

TEST(Cut, ALeadInStartsEarlierAndIsNotJudged) {
  TempDir dir;
  CutOptions o;
  o.replay = seed001_run().replay;
  o.at_s = kCollisionS;
  o.before_s = 5.0;
  o.lead_in_s = 10.0;
  o.out = dir.path() / "lead.json";
  const CutResult cut = cut_replay(o);
  EXPECT_NEAR(cut.start_s, kCollisionS - 15.0, 0.061);
  const sim::Scenario sc = load_scenario(o.out, core::RoadParams{});
  ASSERT_TRUE(sc.cut);
  EXPECT_DOUBLE_EQ(sc.cut->lead_in_s, 10.0);
  EXPECT_DOUBLE_EQ(sc.cut->at_s, kCollisionS);
}

TEST(Cut, AnotherPlannerDrivesTheSameMomentFromTheSameState) {
  TempDir dir;
  CutOptions o;
  o.replay = seed001_run().replay;
  o.at_s = kCollisionS;
  o.out = dir.path() / "cut.json";
  (void)cut_replay(o);
  // The reference planner starts afresh from seed001's world (and its queued path) and does
  // not collide.
  const DriveResult r = drive_scenario(o.out, "reference");
  EXPECT_TRUE(collisions_of(r.report).empty());
  EXPECT_GT(r.report.distance_m, 300.0);
}

TEST(Cut, RefusesWhatItCannotCut) {
  TempDir dir;
  const fs::path bare = dir.path() / "bare.otr";
  DriveOptions d;
  d.minutes = 0.2;
  d.record = bare;
  d.checkpoint_every_s = 0.0;
  (void)drive(d);
  CutOptions o;
  o.replay = bare;
  o.at_s = 5.0;
  o.out = dir.path() / "x.json";
  try {
    (void)cut_replay(o);
    FAIL() << "cut a replay without checkpoints";
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("carries no checkpoints"));
  }
  EXPECT_FALSE(fs::exists(o.out));

  o.replay = seed001_run().replay;
  o.at_s = 500.0;
  EXPECT_THROW((void)cut_replay(o), UsageError);  // past the run's end
  o.at_s = 50.0;
  o.before_s = -1.0;
  EXPECT_THROW((void)cut_replay(o), UsageError);
  o.before_s = 15.0;
  o.out = o.replay;
  EXPECT_THROW((void)cut_replay(o), UsageError);  // would overwrite the replay

  // Cut on the built-in track, driven on another map: refused naming both.
  o.out = dir.path() / "x.json";
  (void)cut_replay(o);
  const fs::path other = dir.path() / "other.csv";
  {
    DriveOptions t;
    std::ofstream(other) << read_file(fs::path(OVERTAKE_SOURCE_DIR) / "data/tracks/seed2.csv");
  }
  DriveOptions on_other;
  on_other.scenario = o.out;
  on_other.minutes_from_scenario = true;
  on_other.map = other;
  try {
    (void)drive(on_other);
    FAIL() << "a cut scenario drove on another map";
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("cut from a run on the map"));
  }
}

// `cut --before 0 --after 0` wrote a scenario of duration_s 0, which `drive` then refused: a
// window that would judge less than a second is refused before anything is written.
TEST(Cut, RefusesAWindowThatWouldJudgeLessThanASecond) {
  TempDir dir;
  CutOptions o;
  o.replay = seed001_run().replay;
  o.out = dir.path() / "w.json";
  const auto error_of = [&](double at, double before, double after, double lead_in) {
    o.at_s = at;
    o.before_s = before;
    o.after_s = after;
    o.lead_in_s = lead_in;
    try {
      (void)cut_replay(o);
    } catch (const UsageError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_THAT(error_of(50.0, 0.0, 0.0, 0.0),
              HasSubstr("--before 0.00 s and --after 0.00 s leave 0.00 s to judge; together "
                        "they must make at least 1 s"));
  EXPECT_THAT(error_of(50.0, 0.5, 0.4, 10.0), HasSubstr("leave 0.90 s to judge"));
  // The run's end clips --after: at its last frame nothing would be judged.
  const replay::Replay r = replay::read_replay(o.replay);
  const double last_t = static_cast<double>(r.frames.back().step) * r.header.step_s;
  EXPECT_THAT(error_of(last_t, 0.0, 5.0, 0.0),
              HasSubstr("the scenario would judge 0.00 s (t " + fixed_text(last_t, 2)));
  // At the run's start the lead-in takes the time before the moment.
  EXPECT_THAT(error_of(0.5, 10.0, 0.5, 10.0),
              HasSubstr("would judge 0.50 s (t 0.50 to 1.00 s, after the lead-in"));
  EXPECT_FALSE(fs::exists(o.out));
  // One second is enough, and `drive` takes what `cut` wrote.
  EXPECT_EQ(error_of(50.0, 0.0, 1.0, 5.0), "");
  const sim::Scenario sc = load_scenario(o.out, core::RoadParams{});
  ASSERT_TRUE(sc.duration_s && sc.cut);
  EXPECT_NEAR(*sc.duration_s - sc.cut->lead_in_s, 1.0, 1e-6);
  EXPECT_NEAR(drive_scenario(o.out, "seed001").report.duration_s, *sc.duration_s, 1e-6);
}

// Replayed traffic beyond what a scenario may carry (16 MB once inflated) would be refused by
// `drive`: `cut` refuses the window and says how long one may be.
TEST(Cut, RefusesReplayedTrafficLargerThanAScenarioMayCarry) {
  TempDir dir;
  DriveOptions d;
  d.policy = "seed001";
  d.seed = 2;
  d.minutes = 6.5;
  d.record = dir.path() / "long.otr";
  (void)drive(d);
  CutOptions o;
  o.replay = *d.record;
  o.at_s = 389.0;
  o.before_s = 3600.0;
  o.after_s = 0.0;
  o.replayed = true;
  o.out = dir.path() / "big.json";
  try {
    (void)cut_replay(o);
    FAIL() << "cut 389 s of replayed traffic";
  } catch (const UsageError& e) {
    EXPECT_THAT(e.what(), HasSubstr("the scenario's replayed traffic for t 0.00 to 389.00 s is"));
    EXPECT_THAT(e.what(), HasSubstr("more than the 16 MB a scenario may carry; cut a window of "
                                    "at most about"));
  }
  EXPECT_FALSE(fs::exists(o.out));
  o.before_s = 60.0;  // a minute is well within it
  (void)cut_replay(o);
  EXPECT_NO_THROW((void)load_scenario(o.out, core::RoadParams{}));
}

TEST(CutScenarioFile, BadBlobsAndMixedKindsAreErrorsNamingTheKey) {
  const auto error_of = [](const std::string& text) {
    try {
      (void)parse_scenario(json::parse(text), "s.json", core::RoadParams{});
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string good_checkpoint = pack_blob("not a checkpoint, but zlib and base64");
  EXPECT_THAT(error_of(R"({"cut": {"traffic": "reactive", "start_s": 1, "at_s": 2,
                                   "checkpoint": "@@@"}})"),
              HasSubstr("scenario.cut.checkpoint: not base64"));
  EXPECT_THAT(error_of(R"({"cut": {"traffic": "reactive", "start_s": 1, "at_s": 2,
                                   "checkpoint": "AAAA"}})"),
              HasSubstr("scenario.cut.checkpoint: damaged or truncated"));
  EXPECT_THAT(error_of(R"({"cut": {"traffic": "sideways", "start_s": 1, "at_s": 2,
                                   "checkpoint": ")" +
                       good_checkpoint + R"("}})"),
              HasSubstr("neither reactive nor replayed"));
  EXPECT_THAT(error_of(R"({"cut": {"traffic": "replayed", "start_s": 1, "at_s": 2,
                                   "checkpoint": ")" +
                       good_checkpoint + R"("}})"),
              HasSubstr("scenario.cut.recorded_traffic: missing"));
  EXPECT_THAT(error_of(R"({"ego": {"lane": 1}, "cut": {"traffic": "reactive", "start_s": 1,
                          "at_s": 2, "checkpoint": ")" +
                       good_checkpoint + R"("}})"),
              HasSubstr("a cut scenario starts from its checkpoint (no ego)"));
  EXPECT_THAT(error_of(R"({"expect": {"reach_lane": {"lane": 7, "by_s": 3}}})"),
              HasSubstr("scenario.expect.reach_lane.lane"));
  EXPECT_THAT(error_of(R"({"expect": {"at_fault": 0}})"),
              HasSubstr("expect.at_fault: unknown key"));
  // A checkpoint that is not one is refused when the drive reads it, naming the scenario.
  TempDir dir;
  const fs::path f = dir.path() / "bad.json";
  std::ofstream(f) << R"({"name": "bad", "cut": {"traffic": "reactive", "start_s": 1,
                          "at_s": 2, "checkpoint": ")"
                   << good_checkpoint << R"("}})";
  try {
    (void)drive_scenario(f, "reference");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("scenario 'bad': cut.checkpoint"));
    EXPECT_THAT(e.what(), HasSubstr("not a checkpoint"));
  }
}

/// The library (data/scenarios): every scenario cut from a failure reproduces it, at the same
/// moment and of the same kind, when driven by the planner that failed.
TEST(ScenarioLibrary, EveryCutScenarioReproducesTheFailureItWasCutFrom) {
  const fs::path dir = fs::path(OVERTAKE_SOURCE_DIR) / "data/scenarios";
  int cuts = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() != ".json") continue;
    const json j = read_json_file(e.path());
    if (!j.contains("cut")) continue;
    ++cuts;
    const std::string policy = j["cut"]["from"]["policy"];
    const std::string incident = j["cut"]["from"]["incident"];
    const double at = j["cut"]["at_s"];
    const DriveResult r = drive_scenario(e.path(), policy);
    // The contact (one collision, however long) that holds the moment, of the same class.
    bool found = false;
    for (const sim::Contact& c : r.report.contacts) {
      const std::string kind(sim::to_string(c.collision.kind));
      if (c.t_s - 1e-6 <= at && at <= c.end_t_s + 1e-6 && incident.find("collision " + kind) == 0) {
        found = true;
      }
    }
    EXPECT_TRUE(found) << e.path().filename() << ": " << policy << " did not repeat " << incident;
  }
  EXPECT_GE(cuts, 20);
}

}  // namespace
}  // namespace overtake::batch
