// Planner time per cycle of the reference policy, on recorded snapshots.
//   ./build/release/overtake_bench --benchmark_filter=Reference
//
// A drive (3 minutes, seed 1, each traffic profile) is recorded once as the telemetry the
// policy saw each cycle. The policy is stateful (it continues its own last plan), so the
// snapshots are replayed in order through a fresh policy: every call then sees exactly the
// state it had when the drive was recorded. Figures: the mean per cycle (Google Benchmark),
// and per-cycle percentiles over a whole replay, both wall-clock and thread CPU time (the
// CPU figures leave out time lost to other processes on a shared machine).

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <vector>

#include "overtake/core/cpu_clock.hpp"
#include "overtake/core/random.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/planner/reference/reference_policy.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/sim/world.hpp"
#include "recording.hpp"

namespace {

using namespace overtake;

constexpr double kRecordedS = 180.0;
constexpr std::uint64_t kSeed = 1;
constexpr std::uint64_t kLatencyStream = 20;  // as run_drive draws K

using benchmarks::config;
using benchmarks::track;

/// The telemetry of every cycle of a recorded drive.
const std::vector<core::Telemetry>& recording(sim::TrafficProfile profile) {
  static std::map<sim::TrafficProfile, std::vector<core::Telemetry>> cache;
  auto& rec = cache[profile];
  if (rec.empty()) {
    rec = benchmarks::record_drive("reference", profile, kSeed,
                                   core::derive_seed(kSeed, kLatencyStream), kRecordedS);
  }
  return rec;
}

sim::TrafficProfile profile_of(const benchmark::State& state) {
  return state.range(0) == 0 ? sim::TrafficProfile::faithful : sim::TrafficProfile::calm;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size()))) - 1;
  return v[std::min(i, v.size() - 1)];
}

// One planning cycle (the recorded cycles in turn).
void BM_ReferencePlanCycle(benchmark::State& state) {
  const auto& rec = recording(profile_of(state));
  auto policy =
      std::make_unique<planner::reference::ReferencePolicy>(track().line, config().planner);
  std::size_t i = 0;
  for (auto _ : state) {
    if (i == rec.size()) {
      state.PauseTiming();
      policy =
          std::make_unique<planner::reference::ReferencePolicy>(track().line, config().planner);
      i = 0;
      state.ResumeTiming();
    }
    benchmark::DoNotOptimize(policy->plan(rec[i++]));
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(std::string(sim::to_string(profile_of(state))));
}
BENCHMARK(BM_ReferencePlanCycle)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// A whole recorded drive, replayed: per-cycle percentiles, wall-clock and thread CPU time.
void BM_ReferenceReplay(benchmark::State& state) {
  const auto& rec = recording(profile_of(state));
  std::vector<double> wall, cpu;
  wall.reserve(rec.size());
  cpu.reserve(rec.size());
  for (auto _ : state) {
    planner::reference::ReferencePolicy policy(track().line, config().planner);
    for (const core::Telemetry& t : rec) {
      const double c0 = core::thread_cpu_us();
      const auto w0 = std::chrono::steady_clock::now();
      benchmark::DoNotOptimize(policy.plan(t));
      wall.push_back(
          std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - w0).count());
      cpu.push_back(core::thread_cpu_us() - c0);
    }
  }
  state.counters["cycles"] = static_cast<double>(rec.size());
  state.counters["wall_p50_us"] = percentile(wall, 0.5);
  state.counters["wall_p99_us"] = percentile(wall, 0.99);
  state.counters["wall_max_us"] = percentile(wall, 1.0);
  state.counters["cpu_p50_us"] = percentile(cpu, 0.5);
  state.counters["cpu_p99_us"] = percentile(cpu, 0.99);
  state.counters["cpu_max_us"] = percentile(cpu, 1.0);
  state.SetLabel(std::string(sim::to_string(profile_of(state))));
}
BENCHMARK(BM_ReferenceReplay)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);

// The trajectory layer alone, on the busiest recorded cycle's request (the most cars near).
void BM_ReferenceTrajectoryLayer(benchmark::State& state) {
  const auto& rec = recording(sim::TrafficProfile::faithful);
  planner::reference::ReferencePolicy policy(track().line, config().planner);
  std::size_t busiest = 0;
  int most = -1;
  for (std::size_t i = 0; i < rec.size(); ++i) {
    (void)policy.plan(rec[i]);
    int near = 0;
    for (const auto& c : policy.last_predictions())
      near += std::abs(c.s_m - rec[i].ego.s_m) < 60.0 ? 1 : 0;
    if (near > most) {
      most = near;
      busiest = i;
    }
  }
  planner::reference::ReferencePolicy replay(track().line, config().planner);
  for (std::size_t i = 0; i < busiest; ++i) (void)replay.plan(rec[i]);
  for (auto _ : state) {
    planner::reference::ReferencePolicy copy = replay;
    benchmark::DoNotOptimize(copy.plan(rec[busiest]));
  }
  state.counters["cars_within_60m"] = most;
}
BENCHMARK(BM_ReferenceTrajectoryLayer)->Unit(benchmark::kMicrosecond);

}  // namespace
