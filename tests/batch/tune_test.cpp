// `overtake tune`: the search on a built-in policy's config keys, a program's placeholder and
// a Python planner's keyword; its record of trials (resume, Ctrl-C); the validation; bad input.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/batch/tune.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/run/config.hpp"
#include "temp_dir.hpp"

namespace overtake {
namespace {

namespace fs = std::filesystem;
using base::read_file;
using base::UsageError;
using batch::parse_tune_constraint;
using batch::parse_tune_param;
using batch::run_tune;
using batch::TuneOutcome;
using batch::TuneSpec;
using nlohmann::json;
using test::TempDir;
using ::testing::HasSubstr;

// Four of the reference planner's keys, started below where they belong (a slow cruise),
// so that a small budget has somewhere to go.
TuneSpec reference_spec(const fs::path& out) {
  TuneSpec s;
  s.policy = "reference";
  s.params = {parse_tune_param("cruise_speed_mps=15:22.21788802040491@16"),
              parse_tune_param("behaviour.min_gap_m=2:6"),
              parse_tune_param("passing_speed_mps=5:12"),
              parse_tune_param("behaviour.change_cost=0:0.02")};
  s.constraints = {parse_tune_constraint("at_fault_collisions<=0"),
                   parse_tune_constraint("incidents<=0")};
  s.seeds = {1, 2};
  s.minutes = 1.0;
  s.trials = 8;
  s.jobs = 2;
  s.out = out;
  return s;
}

// One parameter of a planner from outside, four trials of one seed.
TuneSpec outside_spec(const planners::PlannerFlags& flags, const std::string& policy,
                      const std::string& param, const fs::path& out) {
  TuneSpec s;
  s.policy = policy;
  s.planners = planners::catalog_from_flags(flags);
  s.params = {parse_tune_param(param)};
  s.seeds = {1};
  s.minutes = 0.5;
  s.trials = 4;
  s.jobs = 1;
  s.out = out;
  return s;
}

std::vector<std::string> lines_of(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(Tune, FindsBetterParametersThanItsStartAndValidatesThemOnHeldOutSeeds) {
  const TempDir dir("overtake-tune");
  TuneSpec spec = reference_spec(dir.path() / "out");
  spec.validation_seeds = {11, 12, 13, 14, 15, 16, 17, 18};
  const TuneOutcome o = run_tune(spec, nullptr, nullptr);
  ASSERT_EQ(o.trials.size(), 8U);
  ASSERT_TRUE(o.best.has_value());
  const auto& start = o.trials.front();
  const auto& best = o.trials[static_cast<std::size_t>(*o.best - 1)];
  EXPECT_EQ(start.params.at("cruise_speed_mps"), 16.0);
  EXPECT_DOUBLE_EQ(start.params.at("behaviour.min_gap_m"), 4.0);  // the config's value
  EXPECT_TRUE(best.feasible);
  EXPECT_GT(best.objective, start.objective + 1.0);  // mph, on the training seeds
  // Every trial's numbers as a user would type them: 10 significant digits at most (no
  // 0.9000000000000001 from scaling the unit cube back to the ranges).
  for (const auto& trial : o.trials) {
    for (const auto& [name, value] : trial.params) {
      std::array<char, 32> ten{};
      std::snprintf(ten.data(), ten.size(), "%.10g", value);
      EXPECT_EQ(std::strtod(ten.data(), nullptr), value) << name << " in trial " << trial.number;
    }
  }
  // Every trial is a row; the best is a config file the planner takes.
  EXPECT_EQ(lines_of(spec.out / batch::kTuneTrialsFile).size(), 8U);
  const json best_file = json::parse(read_file(spec.out / batch::kTuneBestFile));
  const run::Config tuned = run::apply_config_json(run::default_config(), best_file, "best.json");
  EXPECT_EQ(tuned.planner.reference.behaviour.cruise_speed_mps, best.params.at("cruise_speed_mps"));
  // The validation: the best against the start on the held-out seeds, paired, judged.
  ASSERT_EQ(o.validations.size(), 1U);
  const json& validation = o.validations[0].comparison;
  ASSERT_EQ(validation["comparisons"].size(), 1U);
  EXPECT_EQ(validation["comparisons"][0]["seeds"], 8);
  const json& speed = validation["comparisons"][0]["figures"]["mean_speed_mph"];
  EXPECT_GT(speed["difference"].get<double>(), 0.0);
  EXPECT_EQ(speed["verdict"], "better");
  EXPECT_THAT(o.summary_markdown, HasSubstr("Validation on held-out seeds"));
  EXPECT_THAT(o.validations[0].verdict, HasSubstr("holds on the held-out seeds"));
  EXPECT_EQ(o.validations[0].map, "the built-in track");
  const std::string page = read_file(spec.out / batch::kTunePageFile);
  EXPECT_THAT(page, HasSubstr("<svg"));
  EXPECT_THAT(page, HasSubstr("Validation on held-out seeds"));
}

TEST(Tune, SearchesOverSeveralMapsAndValidatesOnEach) {
  const TempDir dir("overtake-tune");
  TuneSpec spec = reference_spec(dir.path() / "out");
  const fs::path track = fs::path(OVERTAKE_SOURCE_DIR) / "data" / "tracks" / "sparse.csv";
  spec.maps = {std::nullopt, track};
  spec.minutes = 0.5;
  spec.trials = 3;
  spec.validation_seeds = {11, 12, 13, 14, 15, 16, 17, 18};
  const TuneOutcome o = run_tune(spec, nullptr, nullptr);
  ASSERT_EQ(o.trials.size(), 3U);
  // Each trial drives every seed on each map, and its figures are over all of those runs.
  for (const auto& t : o.trials) EXPECT_EQ(t.figures["runs"], 4.0);
  const fs::path first = spec.out / batch::kTuneTrialsFolder / "0001";
  for (const char* m : {"map-1", "map-2"}) {
    EXPECT_EQ(lines_of(first / m / "runs.jsonl").size(), 2U) << m;
  }
  const json on_track = json::parse(lines_of(first / "map-2" / "runs.jsonl").front());
  EXPECT_EQ(on_track["config"]["map"]["path"], track.string());
  // The manifest names both maps; the validation is one per map, each paired on its own.
  const json manifest = json::parse(read_file(spec.out / batch::kTuneManifestFile));
  EXPECT_EQ(manifest["maps"], json::array({"", track.string()}));
  ASSERT_EQ(o.validations.size(), 2U);
  EXPECT_EQ(o.validations[0].map, "the built-in track");
  EXPECT_EQ(o.validations[1].map, track.string());
  for (const auto& v : o.validations) {
    EXPECT_EQ(v.comparison["comparisons"][0]["seeds"], 8);
    EXPECT_FALSE(v.verdict.empty());
  }
  EXPECT_THAT(o.summary_markdown, HasSubstr("### On " + track.string()));
  EXPECT_THAT(read_file(spec.out / batch::kTunePageFile), HasSubstr("on each of 2 maps"));
}

TEST(Tune, ResumeGoesOnToTheSameTrialsAsOneSearch) {
  const TempDir dir("overtake-tune");
  TuneSpec whole = reference_spec(dir.path() / "whole");
  whole.trials = 5;
  (void)run_tune(whole, nullptr, nullptr);

  // Stopped (as by Ctrl-C) while its third trial runs: two trials kept.
  TuneSpec parts = reference_spec(dir.path() / "parts");
  parts.trials = 5;
  std::atomic<bool> stop{false};
  const TuneOutcome first = run_tune(parts, &stop, [&](const batch::TuneProgress& p) {
    if (p.trial == 3) stop = true;  // as Ctrl-C
  });
  // Two trials kept, or three when the third finished before the stop was seen.
  EXPECT_TRUE(first.interrupted);
  const std::size_t kept = first.trials.size();
  ASSERT_GE(kept, 2U);
  ASSERT_LE(kept, 3U);
  EXPECT_EQ(lines_of(parts.out / batch::kTuneTrialsFile).size(), kept);
  EXPECT_TRUE(first.validations.empty());

  parts.resume = true;
  const TuneOutcome second = run_tune(parts, nullptr, nullptr);
  EXPECT_FALSE(second.interrupted);
  ASSERT_EQ(second.trials.size(), 5U);
  EXPECT_TRUE(second.trials[kept - 1].resumed);
  EXPECT_FALSE(second.trials[kept].resumed);
  EXPECT_EQ(read_file(parts.out / batch::kTuneTrialsFile),
            read_file(whole.out / batch::kTuneTrialsFile));
}

TEST(Tune, TheGlobalOptimisersSearchTheWholeBoxFromTheStartTheSameWayEveryTime) {
  const TempDir dir("overtake-tune");
  for (const std::string algorithm : {"direct", "crs2"}) {
    TuneSpec spec = reference_spec(dir.path() / algorithm);
    spec.algorithm = algorithm;
    spec.trials = 6;
    spec.seeds = {1};
    const TuneOutcome o = run_tune(spec, nullptr, nullptr);
    ASSERT_EQ(o.trials.size(), 6U) << algorithm;
    // Trial 1 is the start whatever the optimiser's first point; the others spread over the
    // box (a local method's second trial moves one parameter by a quarter of its range).
    EXPECT_EQ(o.trials.front().params.at("cruise_speed_mps"), 16.0) << algorithm;
    std::set<double> cruise;
    for (const auto& t : o.trials) cruise.insert(t.params.at("cruise_speed_mps"));
    EXPECT_GE(cruise.size(), 3U) << algorithm;
    // The same search again: the same trials (crs2's random points come from a fixed seed).
    TuneSpec again = spec;
    again.out = dir.path() / (algorithm + "-again");
    (void)run_tune(again, nullptr, nullptr);
    EXPECT_EQ(read_file(again.out / batch::kTuneTrialsFile),
              read_file(spec.out / batch::kTuneTrialsFile))
        << algorithm;
  }
  TuneSpec bad = reference_spec(dir.path() / "bad");
  bad.algorithm = "cmaes";
  try {
    (void)run_tune(bad, nullptr, nullptr);
    ADD_FAILURE() << "an unknown algorithm was taken";
  } catch (const UsageError& e) {
    EXPECT_THAT(e.what(), HasSubstr("--algorithm: unknown 'cmaes' (sbplx, neldermead, bobyqa, "
                                    "cobyla, direct, crs2)"));
  }
}

TEST(Tune, TunesAProgramsPlaceholder) {
  const TempDir dir("overtake-tune");
  planners::PlannerFlags flags;
  flags.commands = {(fs::path(OVERTAKE_BINARY_DIR) / "tests" / "overtake_course_planner").string() +
                    " --speed-mps {speed}"};
  flags.names = {"course"};
  const TuneSpec spec = outside_spec(flags, "course", "speed=8:20@10", dir.path() / "out");
  const TuneOutcome o = run_tune(spec, nullptr, nullptr);
  ASSERT_TRUE(o.best.has_value());
  EXPECT_GT(o.trials[static_cast<std::size_t>(*o.best - 1)].params.at("speed"), 10.0);
  EXPECT_GT(o.trials[static_cast<std::size_t>(*o.best - 1)].objective, o.trials.front().objective);
  EXPECT_THAT(o.best_command, HasSubstr("--speed-mps "));
  EXPECT_THAT(o.best_command, ::testing::Not(HasSubstr("{speed}")));
}

TEST(Tune, TunesAPluginsSetupParameter) {
  const TempDir dir("overtake-tune");
  planners::PlannerFlags flags;
  flags.libs = {OVERTAKE_KEEP_LANE_PLUGIN};
  // Given in its config_json.
  TuneSpec spec = outside_spec(flags, "keep_lane", "cruise_mps=10:21.9@12", dir.path() / "out");
  spec.constraints = {};
  const TuneOutcome o = run_tune(spec, nullptr, nullptr);
  ASSERT_TRUE(o.best.has_value());
  const auto& best = o.trials[static_cast<std::size_t>(*o.best - 1)];
  EXPECT_GT(best.params.at("cruise_mps"), 12.0);
  EXPECT_GT(best.objective, o.trials.front().objective);
  EXPECT_EQ(o.best_config, (json{{"cruise_mps", best.params.at("cruise_mps")}}));
}

TEST(Tune, BadInputIsRefusedBeforeAnyTrialNamingWhatIsWrong) {
  const TempDir dir("overtake-tune");
  const auto refused = [&](TuneSpec spec, const std::string& message) {
    SCOPED_TRACE(message);
    spec.out = dir.path() / "never";
    try {
      (void)run_tune(spec, nullptr, nullptr);
      ADD_FAILURE() << "accepted";
    } catch (const UsageError& e) {
      EXPECT_THAT(e.what(), HasSubstr(message));
    }
    EXPECT_FALSE(fs::exists(spec.out / batch::kTuneTrialsFile));
  };
  TuneSpec s = reference_spec(dir.path());
  s.params = {parse_tune_param("no_such_key=0:1")};
  refused(s, "'no_such_key' is not a numeric key of the config");
  s.params = {parse_tune_param("min_gap_m=0:1")};
  refused(s, "names several config keys");
  s.params = {parse_tune_param("weight=5:100")};
  refused(s, "'weight' is no key's whole name, and is the ending of");
  refused(s, "planner.reference.trajectory.proximity_weight");
  s.params = {parse_tune_param("world.step_s=0.01:0.03")};
  refused(s, "is not the planner's");
  s.params = {parse_tune_param("behaviour.min_gap_m=5:6")};
  refused(s, "starts at 4 (its value in the config), outside its range 5:6");
  s = reference_spec(dir.path());
  s.validation_seeds = {2, 3};
  refused(s, "seed 2 is also a training seed");
  s = reference_spec(dir.path());
  s.objective = "speed";
  refused(s, "--objective: 'speed' is not a figure");

  EXPECT_THROW((void)parse_tune_param("x=2:1"), UsageError);
  EXPECT_THROW((void)parse_tune_param("x=1:2@3"), UsageError);
  EXPECT_THROW((void)parse_tune_param("x"), UsageError);
  EXPECT_THROW((void)parse_tune_constraint("collisions=0"), UsageError);
  EXPECT_THROW((void)parse_tune_constraint("crashes<=0"), UsageError);

  // A folder that holds another search is not resumed as this one.
  TuneSpec a = reference_spec(dir.path() / "a");
  a.trials = 1;
  (void)run_tune(a, nullptr, nullptr);
  TuneSpec b = a;
  b.resume = true;
  b.params[0] = parse_tune_param("cruise_speed_mps=15:22.21788802040491@17");
  try {
    (void)run_tune(b, nullptr, nullptr);
    ADD_FAILURE() << "resumed another search";
  } catch (const UsageError& e) {
    EXPECT_THAT(e.what(), HasSubstr("is another search"));
  }
  b.resume = false;
  try {
    (void)run_tune(b, nullptr, nullptr);
    ADD_FAILURE() << "wrote over a search";
  } catch (const UsageError& e) {
    EXPECT_THAT(e.what(), HasSubstr("holds a search already"));
  }
}

}  // namespace
}  // namespace overtake
