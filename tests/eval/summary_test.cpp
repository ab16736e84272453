// Summaries, pairs and comparisons on benches with known figures: run rows made by hand, so
// that every number the evaluation prints can be checked against what it should be.

#include "overtake/eval/summary.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "overtake/core/random.hpp"
#include "overtake/eval/compare.hpp"
#include "overtake/eval/stats.hpp"

namespace overtake::eval {
namespace {

using nlohmann::json;
using ::testing::HasSubstr;

/// A run's row as runs.jsonl holds it: `mph` for `minutes`, with collisions (the first
/// `at_fault` of them the ego's) and near misses.
json row(const std::string& policy, const std::string& traffic, std::uint64_t seed, double mph,
         int collisions = 0, int at_fault = 0, int near_misses = 0, double minutes = 30.0) {
  const double seconds = 60.0 * minutes;
  json by_kind = {{"ego_hit_car_ahead", at_fault},
                  {"hit_from_behind", collisions - at_fault},
                  {"hit_from_behind_braking", 0},
                  {"ego_lane_change", 0},
                  {"car_cut_in", 0},
                  {"side_contact", 0},
                  {"ego_stopped", 0},
                  {"car_stopped", 0}};
  return {{"index", seed},
          {"config",
           {{"policy", policy}, {"traffic", traffic}, {"seed", seed}, {"map", {{"hash", "abc"}}}}},
          {"distance_miles", mph * seconds / 3600.0},
          {"duration_s", seconds},
          {"best_incident_free_miles", mph * seconds / 3600.0 / (collisions + 1)},
          {"incident_counts",
           {{"collision", collisions},
            {"speeding", 0},
            {"max_acceleration", 0},
            {"max_jerk", 0},
            {"outside_lane", 0}}},
          {"collisions",
           {{"total", collisions},
            {"at_fault", at_fault},
            {"by_kind", by_kind},
            {"rubric_incidents", collisions},
            {"contacts", json::array()}}},
          {"safety",
           {{"min_ttc_ahead_s", near_misses ? json(1.0) : json(nullptr)},
            {"min_ttc_entering_s", nullptr},
            {"min_time_headway_s", 0.8},
            {"time_ttc_below_s", 0.5 * near_misses},
            {"time_headway_below_s", 30.0},
            {"near_miss_episodes", near_misses},
            {"ttc_threshold_s", 1.5},
            {"headway_threshold_s", 1.0}}},
          {"peak",
           {{"acceleration_mps2", 5.0},
            {"jerk_mps3", 3.0},
            {"strict_acceleration_mps2", 6.0},
            {"strict_jerk_mps3", 8.0}}},
          {"timing", {{"p50_us", 50.0}, {"p99_us", 150.0}}},
          {"planner_cycles", 30000},
          {"ended_early", nullptr}};
}

std::vector<RunRow> rows_of(const std::vector<json>& rows) {
  std::vector<RunRow> out;
  for (const json& r : rows) out.push_back(read_run_row(r, "test"));
  return out;
}

TEST(RunRows, AreReadAndBadRowsNamed) {
  const RunRow r = read_run_row(row("reference", "faithful", 3, 44.0, 2, 1, 4), "x");
  EXPECT_EQ(r.policy, "reference");
  EXPECT_EQ(r.seed, 3u);
  EXPECT_DOUBLE_EQ(r.miles, 22.0);
  EXPECT_TRUE(r.contacts_known);
  EXPECT_EQ(r.collisions, 2.0);
  EXPECT_EQ(r.at_fault_collisions, 1.0);
  // A row of a build that counted a collision per second of contact: no collision figures.
  json legacy = row("reference", "faithful", 3, 44.0, 2, 1, 4);
  legacy["collisions"].erase("contacts");
  EXPECT_FALSE(read_run_row(legacy, "x").contacts_known);
  json mismatch = row("reference", "faithful", 3, 44.0, 2, 1, 4);
  mismatch["collisions"]["at_fault"] = 3;
  EXPECT_THAT([&] { (void)read_run_row(mismatch, "r"); },
              ::testing::ThrowsMessage<std::invalid_argument>(
                  HasSubstr("'collisions.at_fault' is more than collisions.total")));
  EXPECT_TRUE(r.has_safety);
  EXPECT_EQ(r.min_ttc_ahead_s, 1.0);
  EXPECT_TRUE(std::isinf(r.min_ttc_entering_s));  // null: never measured
  json bad = row("reference", "faithful", 3, 44.0);
  bad.erase("distance_miles");
  EXPECT_THAT([&] { (void)read_run_row(bad, "b/runs.jsonl, run 3"); },
              ::testing::ThrowsMessage<std::invalid_argument>(
                  HasSubstr("b/runs.jsonl, run 3: 'distance_miles' is missing")));
  bad = row("reference", "faithful", 3, 44.0);
  bad["safety"]["near_miss_episodes"] = "many";
  EXPECT_THAT([&] { (void)read_run_row(bad, "r"); },
              ::testing::ThrowsMessage<std::invalid_argument>(
                  HasSubstr("'safety.near_miss_episodes' is not a number")));
}

TEST(Summary, FiguresAndTheirIntervals) {
  // 20 runs at 40-49.5 mph (30 minutes each), 2 collisions (1 at fault), 3 near misses.
  std::vector<json> rows;
  for (std::uint64_t s = 1; s <= 20; ++s) {
    rows.push_back(row("reference", "faithful", s, 40.0 + 0.5 * static_cast<double>(s - 1),
                       s == 4 ? 2 : 0, s == 4 ? 1 : 0, s % 7 == 0 ? 1 : 0));
  }
  const json summary = summarize(rows_of(rows), {"reference"}, {"faithful"});
  ASSERT_EQ(summary.size(), 1u);
  const json& r = summary[0];
  const double miles = r["total_miles"].get<double>();
  EXPECT_NEAR(miles, 447.5, 1e-9);  // mean of 44.75 mph, 10 hours
  EXPECT_NEAR(r["mean_speed_mph"].get<double>(), 44.75, 1e-6);
  const auto ci = r["mean_speed_mph_ci"];
  // The bootstrap-t reaches about t(19) = 2.09 standard errors each way (sd 2.96, 20 seeds).
  EXPECT_NEAR(44.75 - ci[0].get<double>(), 2.09 * 2.96 / std::sqrt(20.0), 0.25);
  EXPECT_NEAR(ci[1].get<double>() - 44.75, 2.09 * 2.96 / std::sqrt(20.0), 0.25);
  // One at-fault contact in 447.5 miles, from one seed of 20: the overdispersed exact interval
  // (scipy: phi = 1.234; 0.0027-1.445 per 100 mi), wider than Garwood's 0.0057-1.245.
  const json& c = r["collisions"];
  EXPECT_EQ(c["total"], 2.0);
  EXPECT_EQ(c["at_fault"], 1.0);
  EXPECT_EQ(c["rubric_incidents"], 2.0);
  EXPECT_NEAR(c["at_fault_per_100mi"].get<double>(), 100.0 / miles, 1e-12);
  EXPECT_NEAR(c["at_fault_per_100mi_ci"][0].get<double>(), 0.0026846, 1e-6);
  EXPECT_NEAR(c["at_fault_per_100mi_ci"][1].get<double>(), 1.44495, 1e-4);
  EXPECT_EQ(c["by_kind"]["ego_hit_car_ahead"], 1.0);
  EXPECT_EQ(c["by_kind"]["hit_from_behind"], 1.0);
  // Both contacts came from seed 4, but two events are no burst: nothing is said.
  EXPECT_TRUE(r["warnings"].empty());
  // Near misses: 2 episodes (seeds 7 and 14), least TTC 1 s, time gap 0.8 s.
  const json& nm = r["near_misses"];
  EXPECT_EQ(nm["episodes"], 2.0);
  EXPECT_EQ(nm["min_ttc_ahead_s"], 1.0);
  EXPECT_TRUE(nm["min_ttc_entering_s"].is_null());
  EXPECT_NEAR(nm["per_100mi_ci"][0].get<double>(), 0.043439, 1e-5);
  EXPECT_NEAR(nm["per_100mi_ci"][1].get<double>(), 1.74063, 1e-4);
  EXPECT_NEAR(nm["share_headway_below"].get<double>(), 30.0 / 1800.0, 1e-12);
  // How many seeds, by the same methods: 73 for speed (t(n - 1) / sqrt(n) halves), more than
  // twice for a rare rate.
  EXPECT_EQ(r["precision"]["mean_speed_mph"]["seeds_to_halve"], 73);
  const auto halve = r["precision"]["at_fault_collisions_per_100mi"]["seeds_to_halve"].get<int>();
  EXPECT_GT(halve, 40);
  EXPECT_TRUE(r["intervals"].is_null());

  const std::string md = summary_markdown(summary, json::array());
  EXPECT_THAT(md, HasSubstr("| reference | faithful | 20 | 447.5 | 44.75 ("));
  EXPECT_THAT(md, HasSubstr("| 0.22 (0.00–1.44) |"));  // at fault per 100 mi, its interval
  EXPECT_THAT(md, HasSubstr("| reference | faithful | 2 | 1 | 1 | 1 |"));
  const std::string csv = summary_csv(summary);
  EXPECT_THAT(csv, HasSubstr("at_fault_collisions_per_100mi_lo"));
  EXPECT_THAT(csv, HasSubstr(",73,"));  // seeds to halve the speed's interval
}

TEST(Summary, ABurstInOneSeedIsSaid) {
  // 12 collisions in seed 3 (counted again each second, say), 1 in seed 9: the interval over
  // 20 seeds cannot tell how rare such a seed is, and the row says so.
  std::vector<json> rows;
  for (std::uint64_t s = 1; s <= 20; ++s) {
    const int c = s == 3 ? 12 : s == 9 ? 1 : 0;
    rows.push_back(row("x", "faithful", s, 44.0, c, c));
  }
  const json r = summarize(rows_of(rows), {"x"}, {"faithful"})[0];
  ASSERT_FALSE(r["warnings"].empty());
  EXPECT_THAT(r["warnings"][0].get<std::string>(),
              HasSubstr("incidents_per_100mi: one seed holds 92% of the events (12)"));
  EXPECT_THAT(summary_markdown(json::array({r}), json::array()),
              HasSubstr("x / faithful: incidents_per_100mi: one seed holds 92%"));
}

TEST(Summary, ZeroIncidentsHaveAOneSidedUpperBound) {
  std::vector<json> rows;
  for (std::uint64_t s = 1; s <= 20; ++s) rows.push_back(row("reference", "calm", s, 44.0));
  const json r = summarize(rows_of(rows), {"reference"}, {"calm"})[0];
  EXPECT_EQ(r["incidents_per_100mi"], 0.0);
  EXPECT_EQ(r["incidents_per_100mi_ci"][0], 0.0);
  // -ln 0.05 = 3.00 events in 440 miles: 0.68 per 100 miles at 95%, one-sided.
  EXPECT_NEAR(r["incidents_per_100mi_ci"][1].get<double>(), 100.0 * 2.9957 / 440.0, 1e-3);
  EXPECT_THAT(summary_markdown(json::array({r}), json::array()), HasSubstr("| 0.00 (≤ 0.68) |"));
}

TEST(Summary, FewerSeedsThanTheMinimumGetNoIntervals) {
  std::vector<json> rows;
  for (std::uint64_t s = 1; s <= 3; ++s)
    rows.push_back(row("reference", "calm", s, 44.0 + s, 1, 1));
  const json r = summarize(rows_of(rows), {"reference"}, {"calm"})[0];
  EXPECT_EQ(r["intervals"], "too few seeds: 3, need at least 8");
  EXPECT_TRUE(r["mean_speed_mph_ci"].is_null());
  EXPECT_TRUE(r["collisions"]["at_fault_per_100mi_ci"].is_null());
  EXPECT_TRUE(r["precision"]["mean_speed_mph"].is_null());
  EXPECT_NEAR(r["mean_speed_mph"].get<double>(), 46.0, 1e-9);  // the figures themselves stay
  const std::string md = summary_markdown(json::array({r}), json::array());
  EXPECT_THAT(md, HasSubstr("| 46.00 |"));
  EXPECT_THAT(md, HasSubstr("no intervals, too few seeds: 3, need at least 8"));
}

TEST(Summary, RowsThatCountedCollisionsPerSecondHaveNoCollisionFigures) {
  std::vector<json> rows;
  for (std::uint64_t s = 1; s <= 10; ++s) {
    rows.push_back(row("reference", "faithful", s, 44.0, 3, 3));
    rows.back()["collisions"].erase("contacts");
  }
  const json r = summarize(rows_of(rows), {"reference"}, {"faithful"})[0];
  EXPECT_TRUE(r["collisions"].is_null());
  EXPECT_NEAR(r["incidents_per_100mi"].get<double>(), 100.0 * 30.0 / 220.0, 1e-9);
  EXPECT_THAT(summary_markdown(json::array({r}), json::array()),
              HasSubstr("no collision figures (rows written before collisions were counted as "
                        "contacts)"));
  EXPECT_THAT(summary_csv(json::array({r})), HasSubstr("reference,faithful,10,"));
}

TEST(Summary, TheSameRunsGiveTheSameBytes) {
  std::vector<json> rows;
  for (std::uint64_t s = 1; s <= 10; ++s) {
    rows.push_back(row("a", "faithful", s, 40.0 + static_cast<double>(s % 3), s % 4 == 0 ? 1 : 0));
    rows.push_back(row("b", "faithful", s, 41.0 + static_cast<double>(s % 5)));
  }
  const auto runs = rows_of(rows);
  const json s1 = summarize(runs, {"a", "b"}, {"faithful"});
  const json p1 = pair_policies(runs, {"a", "b"}, {"faithful"});
  EXPECT_EQ(s1.dump(), summarize(runs, {"a", "b"}, {"faithful"}).dump());
  EXPECT_EQ(summary_markdown(s1, p1),
            summary_markdown(summarize(runs, {"a", "b"}, {"faithful"}),
                             pair_policies(runs, {"a", "b"}, {"faithful"})));
}

/// A CSV line's fields.
std::vector<std::string> fields_of(const std::string& line) {
  std::vector<std::string> out(1);
  for (const char ch : line) {
    if (ch == ',') {
      out.emplace_back();
    } else {
      out.back() += ch;
    }
  }
  return out;
}

// A planner over the protocol does not say how it planned: its rows' plan_status is null, and
// its share of cycles by status is unknown (null, "–", empty), not all normal. Rows with
// statuses are summed as before; a policy that mixes both gets the shares of the runs that say.
TEST(Summary, PlanStatusSharesAreNullWhenNoRunSaysHowItPlanned) {
  std::vector<json> rows;
  for (std::uint64_t s = 1; s <= 4; ++s) {
    json known = row("builtin", "faithful", s, 44.0);
    known["plan_status"] = {{"cycles", {{"normal", 29000}, {"least_bad", 400}, {"fallback", 600}}},
                            {"first_reason", "braking in the lane"}};
    rows.push_back(known);
    json remote = row("remote", "faithful", s, 44.0);
    remote["plan_status"] = nullptr;
    rows.push_back(remote);
    rows.push_back(s % 2 == 0 ? known : remote);
    rows.back()["config"]["policy"] = "mixed";
  }
  const auto runs = rows_of(rows);
  EXPECT_FALSE(runs[1].plan_status_known);
  EXPECT_EQ(runs[1].plan_status_cycles, (std::array<double, core::kPlanStatusCount>{}));
  EXPECT_TRUE(runs[0].plan_status_known);
  const json summary = summarize(runs, {"builtin", "remote", "mixed"}, {"faithful"});
  ASSERT_EQ(summary.size(), 3u);
  const json& builtin = summary[0]["plan_status_share"];
  EXPECT_DOUBLE_EQ(builtin["least_bad"].get<double>(), 400.0 / 30000.0);
  EXPECT_DOUBLE_EQ(builtin["fallback"].get<double>(), 600.0 / 30000.0);
  EXPECT_NEAR(builtin["normal"].get<double>(), 29000.0 / 30000.0, 1e-12);
  EXPECT_TRUE(summary[1]["plan_status_share"].is_null());
  EXPECT_EQ(summary[2]["plan_status_share"], builtin);  // the two runs that say

  const std::string md = summary_markdown(summary, json::array());
  EXPECT_THAT(
      md, HasSubstr("| builtin | faithful | 5.0 / 3.0 | 6.0 / 8.0 | 50 / 150 | 1.3% / 2.0% | 0 |"));
  EXPECT_THAT(md, HasSubstr("| remote | faithful | 5.0 / 3.0 | 6.0 / 8.0 | 50 / 150 | – | 0 |"));
  const std::string csv = summary_csv(summary);
  std::vector<std::vector<std::string>> lines;
  for (std::size_t at = 0, end = 0; at < csv.size(); at = end + 1) {
    end = csv.find('\n', at);
    lines.push_back(fields_of(csv.substr(at, end - at)));
  }
  ASSERT_EQ(lines.size(), 4u);
  const auto column = [&](const std::string& name) {
    const auto& h = lines[0];
    return static_cast<std::size_t>(std::find(h.begin(), h.end(), name) - h.begin());
  };
  const std::size_t least_bad = column("least_bad_cycle_share");
  const std::size_t fallback = column("fallback_cycle_share");
  ASSERT_LT(fallback, lines[0].size());
  EXPECT_EQ(lines[1][least_bad], "0.01333");
  EXPECT_EQ(lines[1][fallback], "0.02000");
  EXPECT_EQ(lines[2][0], "remote");
  EXPECT_EQ(lines[2][least_bad], "");
  EXPECT_EQ(lines[2][fallback], "");
}

// The lane changes a planner declined, per 100 miles over the group's runs; null when a run
// does not say (a planner over the protocol, a row of a build before they were counted), and
// a bad count is named.
TEST(Summary, LaneChangesDeclinedPer100Miles) {
  std::vector<json> rows;
  for (std::uint64_t s = 1; s <= 4; ++s) {
    json r = row("builtin", "faithful", s, 44.0);
    r["plan_status"] = {{"cycles", {{"normal", 30000}}},
                        {"first_reason", nullptr},
                        {"lane_changes_declined", {{"for_cost", 10 * s}, {"for_safety", s}}}};
    rows.push_back(r);
    json old = r;
    old["config"]["policy"] = "older";
    old["plan_status"].erase("lane_changes_declined");
    rows.push_back(s == 3 ? old : r);
    rows.back()["config"]["policy"] = "older";
  }
  const auto runs = rows_of(rows);
  ASSERT_TRUE(runs[0].changes_declined.has_value());
  EXPECT_EQ(*runs[0].changes_declined, (std::array<double, 2>{10.0, 1.0}));
  const json summary = summarize(runs, {"builtin", "older"}, {"faithful"});
  ASSERT_EQ(summary.size(), 2u);
  double miles = 0.0;
  for (std::size_t i = 0; i < runs.size(); i += 2) miles += runs[i].miles;
  const json& d = summary[0]["lane_changes_declined_per_100mi"];
  EXPECT_NEAR(d["for_cost"].get<double>(), 100.0 * 100.0 / miles, 1e-9);
  EXPECT_NEAR(d["for_safety"].get<double>(), 100.0 * 10.0 / miles, 1e-9);
  EXPECT_TRUE(summary[1]["lane_changes_declined_per_100mi"].is_null());

  json bad = rows[0];
  bad["plan_status"]["lane_changes_declined"]["for_safety"] = -1;
  try {
    (void)rows_of({bad});
    ADD_FAILURE() << "a negative count was read";
  } catch (const std::exception& e) {
    EXPECT_THAT(e.what(), HasSubstr("plan_status.lane_changes_declined.for_safety"));
  }
}

/// 20 seeds of two policies: b's speed on each seed is a's plus `delta` plus noise of `sd`.
std::vector<RunRow> two_policies(double delta, double sd, int a_collisions_every = 0) {
  core::Rng rng(3);
  std::vector<json> rows;
  for (std::uint64_t s = 1; s <= 20; ++s) {
    const double seed_speed = 40.0 + 6.0 * rng.uniform01();  // the seed's traffic
    const int coll = a_collisions_every && s % a_collisions_every == 0 ? 1 : 0;
    rows.push_back(row("a", "faithful", s, seed_speed, coll, coll));
    rows.push_back(row("b", "faithful", s, seed_speed + delta + sd * (rng.uniform01() - 0.5)));
  }
  return rows_of(rows);
}

TEST(Pairs, AKnownDifferenceIsFoundAndNoDifferenceIsNot) {
  // b is 0.5 mph faster on every seed, give or take 0.05: beyond noise, on every seed.
  const json faster = pair_policies(two_policies(0.5, 0.1), {"a", "b"}, {"faithful"});
  ASSERT_EQ(faster.size(), 1u);
  EXPECT_EQ(faster[0]["policy"], "a");
  EXPECT_EQ(faster[0]["versus"], "b");
  EXPECT_EQ(faster[0]["seeds"], 20);
  const json& speed = faster[0]["figures"]["mean_speed_mph"];
  EXPECT_NEAR(speed["difference"].get<double>(), -0.5, 0.05);  // a - b
  EXPECT_LT(speed["ci"][1].get<double>(), 0.0);
  EXPECT_EQ(speed["verdict"], "worse");
  EXPECT_LT(speed["p_adjusted"].get<double>(), 0.05);
  // P(a better than b) over all pairs of runs: the seeds spread 6 mph, the change is 0.5,
  // so a is faster than b in nearly half of the pairs (the share of seeds would say never).
  const double p_improve = speed["probability_of_improvement"].get<double>();
  EXPECT_GT(p_improve, 0.35);
  EXPECT_LT(p_improve, 0.5);
  EXPECT_LE(speed["probability_of_improvement_ci"][0].get<double>(), p_improve);
  // The same policy twice: no difference in anything.
  const json same = pair_policies(two_policies(0.0, 0.0), {"a", "b"}, {"faithful"});
  for (const auto& [name, f] : same[0]["figures"].items()) {
    EXPECT_EQ(f["verdict"], "no difference") << name;
    EXPECT_EQ(f["difference"], 0.0) << name;
  }
  // Noise of 2 mph around no difference: within noise.
  const json noisy = pair_policies(two_policies(0.0, 2.0), {"a", "b"}, {"faithful"});
  const json& ns = noisy[0]["figures"]["mean_speed_mph"];
  EXPECT_LT(ns["ci"][0].get<double>(), 0.0);
  EXPECT_GT(ns["ci"][1].get<double>(), 0.0);
  EXPECT_EQ(ns["verdict"], "no difference");
  // a's at-fault collisions on every second seed: worse beyond noise.
  const json crashes = pair_policies(two_policies(0.0, 0.0, 2), {"a", "b"}, {"faithful"});
  const json& af = crashes[0]["figures"]["at_fault_collisions_per_100mi"];
  EXPECT_GT(af["difference"].get<double>(), 0.0);
  EXPECT_EQ(af["verdict"], "worse");
  EXPECT_EQ(af["probability_of_improvement"], 0.25);  // 10 losses, 10 ties
}

BenchData bench(const std::string& name, std::vector<RunRow> runs, const std::string& map = "abc") {
  BenchData b;
  b.name = name;
  b.manifest = {{"policies", json::array({"a", "b"})},
                {"minutes", 30.0},
                {"steps_per_call", 0},
                {"map", {{"hash", map}}},
                {"params_hash", "p1"}};
  b.runs = std::move(runs);
  return b;
}

TEST(Compare, AnIdenticalBenchIsNoDifference) {
  const auto runs = two_policies(0.3, 1.0, 5);
  const json r = compare_benches(bench("before", runs), bench("after", runs), {});
  ASSERT_EQ(r["comparisons"].size(), 2u);  // a and b, matched by name
  EXPECT_TRUE(r["worse"].empty());
  for (const json& c : r["comparisons"]) {
    for (const auto& [name, f] : c["figures"].items()) {
      EXPECT_EQ(f["verdict"], "no difference") << name;
    }
  }
  EXPECT_THAT(compare_text(r), HasSubstr("No figure got significantly worse."));
}

TEST(Compare, AWorseCandidateIsFoundAndPairsCanBeNamed) {
  // Before: a; after: b, slower by 0.5 mph on every seed (as `--pair a=b`).
  CompareOptions o;
  o.pairs = {{"b", "a"}};
  const auto runs = two_policies(0.5, 0.1);
  const json r = compare_benches(bench("before", runs), bench("after", runs), o);
  ASSERT_EQ(r["comparisons"].size(), 1u);
  EXPECT_EQ(r["comparisons"][0]["figures"]["mean_speed_mph"]["verdict"], "worse");
  ASSERT_EQ(r["worse"].size(), 1u);
  EXPECT_EQ(r["worse"][0], "a / faithful: mean_speed_mph");
  EXPECT_THAT(compare_text(r), HasSubstr("b -> a (faithful, 20 seeds paired)"));
  // Only some figures.
  o.metrics = {Metric::at_fault_collisions_per_100mi};
  const json only = compare_benches(bench("before", runs), bench("after", runs), o);
  EXPECT_EQ(only["comparisons"][0]["figures"].size(), 1u);
  EXPECT_TRUE(only["worse"].empty());
}

TEST(Pairs, VerdictsAreCorrectedForTheFamily) {
  // 7 policies: every policy's speed differs from a's by a small shift whose marginal p-value
  // is near 1-2%, and nothing else differs. Each would read "worse" alone; over the family of
  // 21 pairs x 5 figures, with Holm's correction, they do not.
  core::Rng rng(5);
  std::vector<json> rows;
  const std::vector<std::string> names = {"a", "b", "c", "d", "e", "f", "g"};
  for (std::uint64_t s = 1; s <= 20; ++s) {
    const double seed_speed = 40.0 + 6.0 * rng.uniform01();
    for (std::size_t k = 0; k < names.size(); ++k) {
      const double noise = 1.2 * (rng.uniform01() - 0.5);
      rows.push_back(row(names[k], "faithful", s, seed_speed + noise - (k ? 0.3 : 0.0)));
    }
  }
  const json pairs = pair_policies(rows_of(rows), names, {"faithful"});
  ASSERT_EQ(pairs.size(), 21U);
  EXPECT_EQ(family_size(pairs), 21U);  // only speed can be tested: no event anywhere
  int marginal = 0, judged_worse = 0;
  for (const json& p : pairs) {
    const json& f = p["figures"]["mean_speed_mph"];
    if (f["p_value"].get<double>() < 0.05) ++marginal;
    if (f["verdict"] != "no difference") ++judged_worse;
    EXPECT_GE(f["p_adjusted"].get<double>(), f["p_value"].get<double>());
  }
  EXPECT_GT(marginal, 0);  // without the correction some would be called
  EXPECT_LT(judged_worse, marginal);
  EXPECT_EQ(verdict_method(family_size(pairs))["family_tests"], 21);
}

TEST(Pairs, FewerSeedsThanTheMinimumGetNoVerdict) {
  // Three seeds that move the same way by 0.1 mph: once "better", now no verdict at all.
  std::vector<json> rows;
  for (std::uint64_t s = 1; s <= 3; ++s) {
    rows.push_back(row("a", "faithful", s, 40.0 + static_cast<double>(s)));
    rows.push_back(row("b", "faithful", s, 40.1 + static_cast<double>(s)));
  }
  const json pairs = pair_policies(rows_of(rows), {"a", "b"}, {"faithful"});
  const json& f = pairs[0]["figures"]["mean_speed_mph"];
  EXPECT_EQ(f["verdict"], "too few seeds");
  EXPECT_TRUE(f["ci"].is_null());
  EXPECT_TRUE(f["p_value"].is_null());
  EXPECT_NEAR(f["difference"].get<double>(), -0.1, 1e-9);
  EXPECT_THAT(summary_markdown(json::array(), pairs), HasSubstr("-0.10 (too few seeds)"));
}

TEST(Compare, TooFewSeedsGiveNoVerdictAndSaySo) {
  // One seed, 10% slower: once a zero-width interval and "worse".
  const std::vector<RunRow> before = rows_of({row("a", "faithful", 1, 44.0)});
  const std::vector<RunRow> after = rows_of({row("a", "faithful", 1, 39.6)});
  BenchData b = bench("before", before), a = bench("after", after);
  b.manifest["policies"] = a.manifest["policies"] = json::array({"a"});
  const json r = compare_benches(b, a, {});
  EXPECT_TRUE(r["worse"].empty());
  ASSERT_EQ(r["withheld"].size(), 1U);
  EXPECT_EQ(r["withheld"][0], "a / faithful: too few seeds: 1, need at least 8");
  const std::string text = compare_text(r);
  EXPECT_THAT(text, HasSubstr("no verdict: a / faithful: too few seeds: 1, need at least 8"));
  EXPECT_THAT(text, HasSubstr("too few seeds"));
}

TEST(Compare, OlderRowsAreComparedWhereTheyCanBeAndTheRestNamed) {
  // A bench of a build that counted collisions per second against a new one: speed and the
  // rubric's incidents are compared, collisions are not, and the note says why.
  auto old_rows = two_policies(0.0, 1.0, 4);
  for (RunRow& r : old_rows) r.contacts_known = false;
  const json r =
      compare_benches(bench("old", old_rows), bench("new", two_policies(0.0, 1.0, 4)), {});
  const json& f = r["comparisons"][0]["figures"];
  EXPECT_TRUE(f["at_fault_collisions_per_100mi"].is_null());
  EXPECT_TRUE(f["collisions_per_100mi"].is_null());
  EXPECT_FALSE(f["mean_speed_mph"].is_null());
  bool named = false;
  for (const json& n : r["notes"]) {
    named = named || n.get<std::string>().find("counted as contacts") != std::string::npos;
  }
  EXPECT_TRUE(named);
}

TEST(Compare, RunsThatAreNotPairsAreRefused) {
  const auto runs = two_policies(0.0, 1.0);
  EXPECT_THAT(
      [&] { (void)compare_benches(bench("x", runs), bench("y", runs, "def"), {}); },
      ::testing::ThrowsMessage<NotComparable>(HasSubstr("different maps (x: abc, y: def)")));
  CompareOptions o;
  o.pairs = {{"a", "nope"}};
  EXPECT_THAT([&] { (void)compare_benches(bench("x", runs), bench("y", runs), o); },
              ::testing::ThrowsMessage<std::invalid_argument>(
                  HasSubstr("y has no runs of policy 'nope' (it has a, b)")));
  BenchData other = bench("y", {});
  other.runs = rows_of({row("c", "faithful", 1, 40.0)});
  other.manifest["policies"] = json::array({"c"});
  EXPECT_THAT([&] { (void)compare_benches(bench("x", runs), other, {}); },
              ::testing::ThrowsMessage<NotComparable>(HasSubstr("no policy is in both benches")));
  // Other parameters: compared, with a note.
  BenchData tuned = bench("y", runs);
  tuned.manifest["params_hash"] = "p2";
  const json r = compare_benches(bench("x", runs), tuned, {});
  ASSERT_EQ(r["notes"].size(), 1u);
  EXPECT_THAT(r["notes"][0].get<std::string>(), HasSubstr("the parameters differ"));
}

}  // namespace
}  // namespace overtake::eval
