// The learning environment's pace: agent decisions per second of wall time, N worlds a call
// on T threads (each decision 10 world steps and one plan of the reference's trajectory
// layer). `overtake_bench --benchmark_filter=BM_VecEnv`.

#include <benchmark/benchmark.h>

#include <cstdint>
#include <limits>
#include <vector>

#include "overtake/learn/vec_env.hpp"

namespace {

using overtake::learn::Actions;
using overtake::learn::VecEnv;
using overtake::learn::VecEnvSpec;

// Arg 0: worlds; arg 1: threads. The actions keep the lane, with a lane change and a speed
// change now and then, as an agent's would.
void BM_VecEnvDecisions(benchmark::State& state) {
  VecEnvSpec spec;
  spec.num_envs = static_cast<std::size_t>(state.range(0));
  spec.threads = static_cast<int>(state.range(1));
  spec.seed = 1;
  spec.minutes = 5.0;
  VecEnv env(spec);
  const std::size_t n = env.num_envs();
  std::vector<float> obs(n * env.observation_size()), reward(n);
  std::vector<std::uint8_t> terminated(n), truncated(n);
  std::vector<std::int64_t> act(n, 0);
  env.reset(std::nullopt, obs.data());
  long call = 0;
  for (auto _ : state) {
    for (std::size_t i = 0; i < n; ++i) {
      const long k = (call + static_cast<long>(i) * 7) % 50;
      act[i] = k == 0 ? 1 : k == 25 ? 2 : k == 10 ? 3 : k == 40 ? 4 : 0;
    }
    Actions a;
    a.meta = act.data();
    env.step(a, {obs.data(), reward.data(), terminated.data(), truncated.data()});
    ++call;
    benchmark::DoNotOptimize(obs.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(n));
  state.counters["decisions_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(n),
                         benchmark::Counter::kIsRate);
}
// The worlds alone: a "path" action of no new path each decision (the ego stands), so the
// time is the world's steps, the observation and the reward, without a plan.
void BM_VecEnvWorldsOnly(benchmark::State& state) {
  VecEnvSpec spec;
  spec.num_envs = 64;
  spec.threads = 1;
  spec.seed = 1;
  spec.actions = overtake::learn::ActionKind::path;
  VecEnv env(spec);
  const std::size_t n = env.num_envs();
  std::vector<float> obs(n * env.observation_size()), reward(n);
  std::vector<std::uint8_t> terminated(n), truncated(n);
  std::vector<double> none(n * 2, std::numeric_limits<double>::quiet_NaN());
  env.reset(std::nullopt, obs.data());
  for (auto _ : state) {
    Actions a;
    a.path = none.data();
    a.path_points = 1;
    env.step(a, {obs.data(), reward.data(), terminated.data(), truncated.data()});
    benchmark::DoNotOptimize(obs.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(n));
}
BENCHMARK(BM_VecEnvWorldsOnly)->Unit(benchmark::kMillisecond)->MinTime(2.0)->UseRealTime();

BENCHMARK(BM_VecEnvDecisions)
    ->Args({64, 1})
    ->Args({64, 2})
    ->Args({1, 1})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(3.0)
    ->UseRealTime();

}  // namespace
