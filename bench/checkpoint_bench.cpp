// World checkpoints (README: "Figures"): taking one (the run's state and the reference
// planner's, encoded as replays and cut scenarios store it) and restoring one into a new
// world and policy, 5 minutes into a reference drive in faithful or calm traffic.
//   ./build/release/overtake_bench --benchmark_filter=Checkpoint

#include <benchmark/benchmark.h>

#include <memory>
#include <string>

#include "overtake/planner/policy.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/scenario_file.hpp"
#include "overtake/sim/checkpoint.hpp"
#include "overtake/sim/run.hpp"
#include "overtake/sim/world.hpp"

namespace {

using namespace overtake;

const run::Track& track() {
  static const auto t = run::load_track(std::nullopt);
  return *t;
}

sim::TrafficProfile profile_of(const benchmark::State& state) {
  return state.range(0) == 0 ? sim::TrafficProfile::faithful : sim::TrafficProfile::calm;
}

/// A reference drive of 5 minutes, stopped at a cycle's start.
struct Drive {
  run::Config config = run::default_config();
  std::unique_ptr<sim::World> world;
  std::unique_ptr<planner::Policy> policy;
  std::unique_ptr<sim::Stepper> run;
  explicit Drive(sim::TrafficProfile profile) {
    world = std::make_unique<sim::World>(track().map, track().line, config.world, profile, 7);
    policy = planner::make_policy("reference", track().line, config.planner);
    run = std::make_unique<sim::Stepper>(*world, sim::RunOptions{});
    while (world->time_s() < 300.0) {
      run->apply(policy->plan(run->telemetry()), 0.0);
      run->step_one_call();
    }
  }
  [[nodiscard]] sim::Checkpoint take() {
    sim::Checkpoint c;
    c.info.step = world->steps();
    c.info.t_s = world->time_s();
    c.info.traffic = std::string(sim::to_string(world->traffic().profile()));
    c.run = run->save();
    c.planner = planner::save_policy_state(*policy);
    return c;
  }
};

void BM_CheckpointTake(benchmark::State& state) {
  Drive d(profile_of(state));
  std::size_t bytes = 0;
  for (auto _ : state) {
    const std::string encoded = sim::encode_checkpoint(d.take());
    bytes = encoded.size();
    benchmark::DoNotOptimize(encoded.data());
  }
  const std::string encoded = sim::encode_checkpoint(d.take());
  state.counters["bytes"] = static_cast<double>(bytes);
  state.counters["packed_bytes"] = static_cast<double>(run::pack_blob(encoded).size());
  state.SetLabel(state.range(0) == 0 ? "faithful" : "calm");
}
BENCHMARK(BM_CheckpointTake)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// Restoring a checkpoint: decoding it, then the run's state and the planner's, into a world
// and a reference planner made for it (state.range(1) == 1) or made once beforehand (0: what
// restoring costs beyond making them).
void BM_CheckpointRestore(benchmark::State& state) {
  Drive d(profile_of(state));
  const std::string encoded = sim::encode_checkpoint(d.take());
  const run::Config config = run::default_config();
  const bool make = state.range(1) == 1;
  auto world =
      std::make_unique<sim::World>(track().map, track().line, config.world, profile_of(state), 1);
  auto policy = planner::make_policy("reference", track().line, config.planner);
  for (auto _ : state) {
    if (make) {
      world = std::make_unique<sim::World>(track().map, track().line, config.world,
                                           profile_of(state), 1);
      policy = planner::make_policy("reference", track().line, config.planner);
    }
    const sim::Checkpoint c = sim::decode_checkpoint(encoded, "bench");
    (void)planner::restore_policy_state(*policy, c.planner);
    sim::RunOptions opts;
    opts.restore = c.run;
    sim::Stepper run(*world, opts);
    benchmark::DoNotOptimize(run.end_step());
  }
  state.SetLabel(std::string(state.range(0) == 0 ? "faithful" : "calm") +
                 (make ? ", world and planner made" : ", state only"));
}
BENCHMARK(BM_CheckpointRestore)
    ->Args({0, 0})
    ->Args({1, 0})
    ->Args({0, 1})
    ->Args({1, 1})
    ->Unit(benchmark::kMicrosecond);

// A branch of `overtake risk` (batch/risk_world.cpp): the run's state and the planner's,
// held as taken (not encoded), restored into the same world and planner with every random
// generator reseeded, then one planner cycle driven from it; and the save that precedes a
// branch.
void BM_RiskBranch(benchmark::State& state) {
  Drive d(profile_of(state));
  const std::string run_state = d.run->save();
  const std::string policy_state = planner::save_policy_state(*d.policy);
  std::uint64_t seed = 1;
  for (auto _ : state) {
    (void)planner::restore_policy_state(*d.policy, policy_state);
    sim::RunOptions opts;
    opts.restore = run_state;
    opts.reseed = ++seed;
    sim::Stepper run(*d.world, opts);
    benchmark::DoNotOptimize(run.end_step());
  }
  state.SetLabel(state.range(0) == 0 ? "faithful" : "calm");
}
BENCHMARK(BM_RiskBranch)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_RiskSave(benchmark::State& state) {
  Drive d(profile_of(state));
  for (auto _ : state) {
    std::string run_state = d.run->save();
    std::string policy_state = planner::save_policy_state(*d.policy);
    benchmark::DoNotOptimize(run_state.data());
    benchmark::DoNotOptimize(policy_state.data());
  }
  state.SetLabel(state.range(0) == 0 ? "faithful" : "calm");
}
BENCHMARK(BM_RiskSave)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
