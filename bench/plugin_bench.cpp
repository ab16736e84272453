// The cost of the plugin boundary (overtake/planner_plugin.h) per planner call.
//   ./build/release/overtake_bench --benchmark_filter=Plugin
//
// A minute of a drive (seed 1, faithful traffic, the walkthrough policy) is recorded once as
// the telemetry of each cycle; each benchmark replays it, in order, through one policy:
// - PluginBoundary/InProcess: the minimal planner (keep the previous path, extend it
//   straight) as an in-process policy;
// - PluginBoundary/Plugin: the same planner as a plugin (tests/plugin/plugins/minimal.cpp):
//   the difference is the boundary's cost (the telemetry converted to the original's units
//   and arrays, the call through the library, the answer checked and copied back);
// - PluginBoundary/PluginWatched: the plugin as drive and bench run it, each call watched
//   for its reply timeout (planners::watch_policy): the difference is the watchdog's cost;
// - PluginPolicies/Walkthrough and PluginPolicies/KeepLane: a built-in policy and the
//   example plugin (examples/plugin), for scale.
// The plugins are the modules the tests build (OVERTAKE_BUILD_TESTS).

#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "overtake/planner/policy.hpp"
#include "overtake/planners/plan_watch.hpp"
#include "overtake/plugin/plugin.hpp"
#include "overtake/sim/world.hpp"
#include "recording.hpp"

namespace {

using namespace overtake;

constexpr double kRecordedS = 60.0;
constexpr std::uint64_t kSeed = 1;

using benchmarks::config;
using benchmarks::track;

const std::vector<core::Telemetry>& recording() {
  static const std::vector<core::Telemetry> rec = benchmarks::record_drive(
      "walkthrough", sim::TrafficProfile::faithful, kSeed, kSeed, kRecordedS);
  return rec;
}

/// tests/plugin/plugins/minimal.cpp, in process: the previous path, extended straight along
/// its last heading at the ego's speed (at least 1 m/s) to 50 points.
class MinimalPolicy final : public planner::Policy {
 public:
  explicit MinimalPolicy(double step_s) : step_s_(step_s) {}
  core::PlanResult plan(const core::Telemetry& t) override {
    std::vector<core::Vec2> out(t.previous_path.begin(), t.previous_path.end());
    core::Vec2 p = t.ego.position;
    double yaw = t.ego.yaw_rad;
    const double step = std::fmax(t.ego.speed_mps, 1.0) * step_s_;
    if (out.size() >= 2) {
      p = out.back();
      const core::Vec2 before = out[out.size() - 2];
      yaw = std::atan2(p.y - before.y, p.x - before.x);
    }
    while (out.size() < 50) {
      p = {p.x + step * std::cos(yaw), p.y + step * std::sin(yaw)};
      out.push_back(p);
    }
    return core::normal_plan(std::move(out));
  }

 private:
  double step_s_;
};

/// Replays the recording through policies made by `make`, one call per iteration.
template <class Make>
void replay(benchmark::State& state, const Make& make) {
  const auto& rec = recording();
  auto policy = make();
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(policy->plan(rec[i]));
    if (++i == rec.size()) {
      i = 0;
      state.PauseTiming();
      policy = make();  // a fresh one: the recording starts from the beginning again
      state.ResumeTiming();
    }
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_PluginBoundary_InProcess(benchmark::State& state) {
  replay(state, [] { return std::make_unique<MinimalPolicy>(config().planner.step_s); });
}
BENCHMARK(BM_PluginBoundary_InProcess)->Name("PluginBoundary/InProcess");

void BM_PluginPolicies_Walkthrough(benchmark::State& state) {
  replay(state, [] { return planner::make_policy("walkthrough", track().line, config().planner); });
}
BENCHMARK(BM_PluginPolicies_Walkthrough)->Name("PluginPolicies/Walkthrough");

#ifdef OVERTAKE_MINIMAL_PLUGIN
void BM_PluginBoundary_Plugin(benchmark::State& state) {
  const plugin::LoadedPlugin p = plugin::load_plugin(OVERTAKE_MINIMAL_PLUGIN);
  replay(state, [&p] { return p.make(track().line, config().planner); });
}
BENCHMARK(BM_PluginBoundary_Plugin)->Name("PluginBoundary/Plugin");

void BM_PluginBoundary_PluginWatched(benchmark::State& state) {
  const plugin::LoadedPlugin p = plugin::load_plugin(OVERTAKE_MINIMAL_PLUGIN);
  replay(state, [&p] {
    return planners::watch_policy(p.make(track().line, config().planner), "the plugin minimal", 5.0,
                                  nullptr);
  });
}
BENCHMARK(BM_PluginBoundary_PluginWatched)->Name("PluginBoundary/PluginWatched");

void BM_PluginPolicies_KeepLane(benchmark::State& state) {
  const plugin::LoadedPlugin p = plugin::load_plugin(OVERTAKE_KEEP_LANE_PLUGIN);
  replay(state, [&p] { return p.make(track().line, config().planner); });
}
BENCHMARK(BM_PluginPolicies_KeepLane)->Name("PluginPolicies/KeepLane");
#endif

}  // namespace
