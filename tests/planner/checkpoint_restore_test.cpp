// World checkpoints restore exactly: a run restored from a checkpoint taken at step N and run
// on reports the same, byte for byte (timing aside), as the run that never stopped. For both
// traffic profiles, several seeds and times, with the reference planner (whose own state is
// part of the checkpoint) and a seed policy.

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "overtake/planner/policy.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "overtake/sim/checkpoint.hpp"
#include "overtake/sim/run.hpp"
#include "overtake/sim/world.hpp"

namespace overtake::planner {
namespace {

/// Keeps every checkpoint the run hands out.
class Keeper final : public sim::RunObserver {
 public:
  void on_frame(const sim::Frame& /*frame*/, std::span<const sim::Incident> /*new*/) override {}
  void on_path(std::span<const core::Vec2> /*path*/) override {}
  void on_checkpoint(const sim::Checkpoint& c) override { kept.push_back(c); }
  std::vector<sim::Checkpoint> kept;
};

std::string report_text(const sim::RunReport& r) {
  nlohmann::json j = run::report_to_json(r, {});
  j.erase("timing");
  return j.dump();
}

struct Case {
  std::string policy;
  sim::TrafficProfile profile;
  std::uint64_t seed;
  double duration_s;
};

const run::Track& default_track() {
  static const auto track = run::load_track(std::nullopt);
  return *track;
}

/// Runs the case whole, keeping checkpoints every `every_s`; returns its report.
std::string run_whole(const Case& c, double every_s, Keeper& keeper) {
  const run::Config config = run::default_config();
  const run::Track& track = default_track();
  sim::World world(track.map, track.line, config.world, c.profile, c.seed);
  auto policy = make_policy(c.policy, track.line, config.planner);
  sim::RunOptions opts;
  opts.duration_s = c.duration_s;
  opts.seed = c.seed;
  opts.observer = &keeper;
  opts.checkpoint_every_s = every_s;
  opts.planner_state = [&] { return save_policy_state(*policy); };
  return report_text(sim::run_drive(
      world, [&](const core::Telemetry& t) { return policy->plan(t); }, opts));
}

/// Restores a checkpoint (through its bytes) into a new world and policy and runs on.
std::string run_restored(const Case& c, sim::Checkpoint checkpoint) {
  checkpoint.info.traffic = sim::to_string(c.profile);
  checkpoint.info.policy = c.policy;
  const sim::Checkpoint read = sim::decode_checkpoint(sim::encode_checkpoint(checkpoint), "test");
  EXPECT_EQ(read, checkpoint);
  const run::Config config = run::default_config();
  const run::Track& track = default_track();
  // Another seed: the random streams are part of the state.
  sim::World world(track.map, track.line, config.world, c.profile, c.seed + 1000);
  auto policy = make_policy(c.policy, track.line, config.planner);
  EXPECT_TRUE(restore_policy_state(*policy, read.planner));
  sim::RunOptions opts;
  opts.duration_s = 1.0;  // the checkpoint's end counts, not this
  opts.seed = c.seed + 1000;
  opts.restore = read.run;
  return report_text(sim::run_drive(
      world, [&](const core::Telemetry& t) { return policy->plan(t); }, opts));
}

TEST(CheckpointRestore, RunsOnExactlyAsTheRunThatNeverStopped) {
  const std::vector<Case> cases = {
      {"reference", sim::TrafficProfile::faithful, 1, 120.0},
      {"reference", sim::TrafficProfile::faithful, 7, 120.0},
      {"reference", sim::TrafficProfile::calm, 2, 120.0},
      {"reference", sim::TrafficProfile::calm, 9, 120.0},
      {"seed001", sim::TrafficProfile::faithful, 3, 120.0},
      {"seed003", sim::TrafficProfile::calm, 4, 120.0},
  };
  for (const Case& c : cases) {
    Keeper keeper;
    const std::string whole = run_whole(c, 23.0, keeper);
    ASSERT_GE(keeper.kept.size(), 6U);
    // The first (t = 0), one early, one mid-run, one late.
    for (const std::size_t k :
         {std::size_t{0}, std::size_t{1}, keeper.kept.size() / 2, keeper.kept.size() - 1}) {
      const sim::Checkpoint& cp = keeper.kept[k];
      EXPECT_EQ(run_restored(c, cp), whole)
          << c.policy << ", " << sim::to_string(c.profile) << ", seed " << c.seed
          << ", restored at t = " << cp.info.t_s << " s (step " << cp.info.step << ")";
    }
  }
}

TEST(CheckpointRestore, TheSameRunGivesTheSameCheckpointBytes) {
  const Case c{"reference", sim::TrafficProfile::faithful, 5, 60.0};
  Keeper a;
  Keeper b;
  (void)run_whole(c, 20.0, a);
  (void)run_whole(c, 20.0, b);
  ASSERT_EQ(a.kept.size(), b.kept.size());
  for (std::size_t i = 0; i < a.kept.size(); ++i) {
    EXPECT_EQ(sim::encode_checkpoint(a.kept[i]), sim::encode_checkpoint(b.kept[i]));
  }
}

TEST(CheckpointRestore, ARunStateDoesNotFitAnotherProfile) {
  const Case c{"reference", sim::TrafficProfile::faithful, 5, 20.0};
  Keeper keeper;
  (void)run_whole(c, 10.0, keeper);
  ASSERT_FALSE(keeper.kept.empty());
  const run::Config config = run::default_config();
  const run::Track& track = default_track();
  sim::World calm(track.map, track.line, config.world, sim::TrafficProfile::calm, 5);
  sim::RunOptions opts;
  opts.restore = keeper.kept.back().run;
  try {
    sim::Stepper stepper(calm, opts);
    FAIL() << "a faithful run's state was restored into calm traffic";
  } catch (const core::StateError& e) {
    EXPECT_NE(std::string(e.what()).find("calm traffic"), std::string::npos) << e.what();
  }
}

TEST(CheckpointRestore, APolicyRefusesAnotherPolicysState) {
  const run::Config config = run::default_config();
  const run::Track& track = default_track();
  auto seed = make_policy("seed001", track.line, config.planner);
  auto reference = make_policy("reference", track.line, config.planner);
  const std::string state = save_policy_state(*seed);
  ASSERT_FALSE(state.empty());
  EXPECT_THROW((void)restore_policy_state(*reference, state), core::StateError);
}

}  // namespace
}  // namespace overtake::planner
