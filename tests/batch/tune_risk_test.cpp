// `overtake tune --max-risk`: each trial's rate is `overtake risk`'s estimate on the same runs,
// the limit decides which trials are feasible, the validation estimates the start and the best
// on runs of their own; a knob a trial turns moves the keys it moves; bad input is refused.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/batch/risk.hpp"
#include "overtake/batch/tune.hpp"
#include "overtake/planner/reference/assertiveness.hpp"
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

// The assertiveness knob from its assertive end, near misses (common enough to count in
// minutes) estimated over 16 one-minute runs a trial.
TuneSpec knob_spec(const fs::path& out) {
  TuneSpec s;
  s.policy = "reference";
  s.params = {parse_tune_param("assertiveness=0:1@1")};
  s.seeds = {1, 2};
  s.minutes = 1.0;
  s.trials = 4;
  s.jobs = 2;
  s.out = out;
  batch::TuneRisk r;
  r.event = batch::parse_risk_event("near-miss");
  r.hours = 0.2;
  r.validation_hours = 0.2;
  r.first_seed = 1001;
  r.rel_error = 0.0;
  s.risk = r;
  return s;
}

double figure(const batch::TuneTrial& t, const char* name) {
  return t.figures.at(name).get<double>();
}

TEST(TuneRisk, EachTrialsRateIsRisksEstimateOnTheSameRunsAndTheLimitDecidesWhichAreFeasible) {
  const TempDir dir;
  // Without a limit: every trial's rate, the search free to go where speed is.
  const TuneSpec free = knob_spec(dir.path() / "free");
  const TuneOutcome a = run_tune(free, nullptr, nullptr);
  ASSERT_GE(a.trials.size(), 2U);
  std::vector<double> rates;
  for (const auto& t : a.trials) {
    rates.push_back(figure(t, "risk_per_100mi"));
    EXPECT_GT(figure(t, "risk_miles"), 5.0);
    EXPECT_LE(figure(t, "risk_low_per_100mi"), rates.back());
    EXPECT_GE(figure(t, "risk_high_per_100mi"), rates.back());
    EXPECT_TRUE(t.feasible);
  }
  const auto [low, high] = std::minmax_element(rates.begin(), rates.end());
  ASSERT_LT(*low, *high) << "the knob moves the near-miss rate";

  // The first trial's rate is what `overtake risk` estimates for its config on those runs.
  batch::RiskSpec r;
  r.policy = "reference";
  r.config = free.out / "trials" / "0001" / "config.json";
  r.event = free.risk->event;
  r.minutes = 1.0;
  r.first_seed = 1001;
  r.budget_hours = 0.2;
  r.rel_error = 0.0;
  r.scenarios = 0;
  r.jobs = 1;
  r.out = dir.path() / "risk";
  const batch::RiskOutcome direct = batch::run_risk(r, nullptr, nullptr);
  const json j = batch::risk_json(r, direct);
  EXPECT_NEAR(figure(a.trials[0], "risk_per_100mi"), j["rate_per_100mi"].get<double>(), 1e-9);
  EXPECT_NEAR(figure(a.trials[0], "risk_high_per_100mi"), j["ci95_per_100mi"][1].get<double>(),
              1e-9);

  // A limit between the rates: exactly the trials at or under it are feasible, and the best
  // is one of them. The trial of the start is the same trial in both searches.
  TuneSpec limited = knob_spec(dir.path() / "limited");
  limited.risk->max_per_100mi = (*low + *high) / 2.0;
  limited.validation_seeds = {3, 4};
  const TuneOutcome b = run_tune(limited, nullptr, nullptr);
  EXPECT_DOUBLE_EQ(figure(b.trials[0], "risk_per_100mi"), rates[0]);
  bool some_out = false;
  for (const auto& t : b.trials) {
    const bool within = figure(t, "risk_per_100mi") <= *limited.risk->max_per_100mi;
    EXPECT_EQ(t.feasible, within) << "trial " << t.number;
    if (!within) {
      some_out = true;
      ASSERT_FALSE(t.violations.empty());
      EXPECT_THAT(t.violations[0], HasSubstr("risk_per_100mi = "));
    }
  }
  ASSERT_TRUE(b.best.has_value());
  EXPECT_LE(figure(b.trials[static_cast<std::size_t>(*b.best - 1)], "risk_per_100mi"),
            *limited.risk->max_per_100mi);
  EXPECT_TRUE(some_out || *high <= *limited.risk->max_per_100mi);

  // The validation: the start and the best on runs of their own, after the trials' last.
  ASSERT_EQ(b.validations.size(), 1U);
  const json& v = b.validations[0].risk;
  ASSERT_TRUE(v.is_object());
  EXPECT_GT(v["first_seed"].get<std::uint64_t>(), 1001U + 15U);
  EXPECT_GT(v["best"]["miles"].get<double>(), 5.0);
  EXPECT_GT(v["start"]["miles"].get<double>(), 5.0);
  EXPECT_TRUE(fs::exists(limited.out / "validation" / "risk-best" / "risk.json"));
  EXPECT_THAT(b.validations[0].risk_verdict, HasSubstr("On held-out runs the best's near-miss"));
  EXPECT_THAT(b.summary_markdown, HasSubstr("risk_per_100mi <= "));
  EXPECT_THAT(b.summary_markdown, HasSubstr(b.validations[0].risk_verdict));
  const std::string page = read_file(limited.out / "tune.html");
  EXPECT_THAT(page, HasSubstr("aria-label='objective against risk'"));
  EXPECT_THAT(page, HasSubstr("stroke-dasharray"));  // the limit

  // A resume of the same search runs no trial again; one of another risk is refused.
  TuneSpec again = limited;
  again.resume = true;
  const TuneOutcome c = run_tune(again, nullptr, nullptr);
  ASSERT_EQ(c.trials.size(), b.trials.size());
  for (const auto& t : c.trials) EXPECT_TRUE(t.resumed);
  EXPECT_EQ(c.best, b.best);
  TuneSpec other = again;
  other.risk->hours = 0.4;
  try {
    (void)run_tune(other, nullptr, nullptr);
    ADD_FAILURE() << "a resume of another risk budget was taken";
  } catch (const UsageError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("is another search"));
  }
}

TEST(TuneRisk, ATrialTurnsAKnobThatMovesTheKeysTheStartingFileLeavesAlone) {
  const TempDir dir;
  // The starting file sets one key the knob moves by hand: the trial keeps it, and the knob
  // moves the others.
  const fs::path start = dir.path() / "start.json";
  base::write_file_atomic(start,
                          R"({"planner": {"reference": {"behaviour": {"min_gap_m": 3.5}}}})");
  TuneSpec s;
  s.policy = "reference";
  s.config = start;
  s.params = {parse_tune_param("assertiveness=0:1@1")};
  s.seeds = {1};
  s.minutes = 1.0;
  s.trials = 1;
  s.jobs = 1;
  s.out = dir.path() / "o";
  const TuneOutcome o = run_tune(s, nullptr, nullptr);
  ASSERT_EQ(o.trials.size(), 1U);
  const run::Config c = run::load_config(s.out / "trials" / "0001" / "config.json");
  const run::Config defaults = run::default_config();
  EXPECT_EQ(c.planner.reference.assertiveness, 1.0);
  EXPECT_EQ(c.planner.reference.behaviour.min_gap_m, 3.5);
  EXPECT_EQ(
      c.planner.reference.behaviour.change_front_factor,
      planner::with_assertiveness(defaults.planner.reference, 1.0).behaviour.change_front_factor);
  EXPECT_NE(c.planner.reference.behaviour.change_front_factor,
            defaults.planner.reference.behaviour.change_front_factor);
}

std::string refusal(const TuneSpec& s) {
  try {
    batch::check_tune_spec(s);
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

TEST(TuneRisk, BadRiskInputIsRefusedNamingTheFlag) {
  const TempDir dir;
  TuneSpec no_risk = knob_spec(dir.path() / "a");
  no_risk.risk.reset();
  no_risk.constraints = {parse_tune_constraint("risk_per_100mi<=1")};
  EXPECT_THAT(refusal(no_risk), HasSubstr("give --max-risk RATE or --risk-hours"));
  no_risk.constraints.clear();
  no_risk.objective = "risk_high_per_100mi";
  EXPECT_THAT(refusal(no_risk), HasSubstr("'risk_high_per_100mi' is a figure"));

  TuneSpec short_runs = knob_spec(dir.path() / "b");
  short_runs.minutes = 0.5;
  EXPECT_THAT(refusal(short_runs), HasSubstr("--minutes: a trial's risk"));

  TuneSpec negative = knob_spec(dir.path() / "c");
  negative.risk->max_per_100mi = -1.0;
  EXPECT_THAT(refusal(negative), HasSubstr("--max-risk"));
  TuneSpec no_hours = knob_spec(dir.path() / "d");
  no_hours.risk->hours = 0.0;
  EXPECT_THAT(refusal(no_hours), HasSubstr("--risk-hours"));

  // The trials' risk runs on a held-out seed, the validation's on a training one.
  TuneSpec held_out = knob_spec(dir.path() / "e");
  held_out.validation_seeds = {1005};
  EXPECT_THAT(refusal(held_out), HasSubstr("1005 is a held-out seed"));
  TuneSpec training = knob_spec(dir.path() / "f");
  training.seeds = {1001 + 16};
  training.validation_seeds = {3};
  EXPECT_THAT(refusal(training), HasSubstr("is a training seed"));
  EXPECT_THAT(refusal(training), HasSubstr("--risk-first-seed"));
  EXPECT_EQ(refusal(knob_spec(dir.path() / "g")), "");
}

}  // namespace
}  // namespace overtake
