// Speed figures of the simulator and the planners (README: "Figures").
//   ./build/release/overtake_bench                       all
//   ./build/release/overtake_bench --benchmark_filter=WorldStep

#include <benchmark/benchmark.h>

#include <fstream>
#include <memory>
#include <string>

#include "overtake/core/units.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/sim/scorecard.hpp"
#include "overtake/sim/world.hpp"

namespace {

using namespace overtake;

const run::Track& default_track() {
  static const auto track = run::load_track(std::nullopt);
  return *track;
}

// A path along the middle lane at a steady 21 m/s, `n` points from the ego's position.
std::vector<core::Vec2> lane_path(const sim::World& w, int n) {
  std::vector<core::Vec2> path;
  const double s0 = w.ego().frenet.s_m;
  for (int i = 1; i <= n; ++i) path.push_back(w.line().to_cartesian({s0 + 0.42 * i, 6.0}));
  return path;
}

sim::World profile_world(const benchmark::State& state, const core::Map& map,
                         const core::ReferenceLine& line) {
  const auto profile =
      state.range(0) == 0 ? sim::TrafficProfile::faithful : sim::TrafficProfile::calm;
  return {map, line, run::default_config().world, profile, 1};
}

// Steps `world` along lane 1 (its path refilled off the clock), `after_step` on the clock
// after each step; labelled with the traffic profile (state.range(0): 0 faithful, 1 calm).
template <class AfterStep>
void time_steps(benchmark::State& state, sim::World& world, AfterStep after_step) {
  world.apply_path(lane_path(world, 1000));
  for (auto _ : state) {
    if (world.queue().size() < 3) {
      state.PauseTiming();
      world.apply_path(lane_path(world, 1000));
      state.ResumeTiming();
    }
    world.step();
    after_step();
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(state.range(0) == 0 ? "faithful" : "calm");
}

// One world step: 12 cars decide and move, the ego moves, bodies that touch are separated.
void BM_WorldStep(benchmark::State& state) {
  const auto& track = default_track();
  sim::World world = profile_world(state, track.map, track.line);
  time_steps(state, world, [] {});
}
BENCHMARK(BM_WorldStep)->Arg(0)->Arg(1);

// One world step and the scorecard that watches it, as in a drive: the safety monitor (TTC,
// headway, the class of a contact), the referee and the lane tracker. Less BM_WorldStep: what
// the scorecard costs per step.
void BM_ScoredStep(benchmark::State& state) {
  const auto& track = default_track();
  sim::World world = profile_world(state, track.map, track.line);
  world.apply_path(lane_path(world, 1600));
  for (int i = 0; i < 1500; ++i) world.step();  // 30 s: every car placed
  sim::Scorecard scorecard(world);
  time_steps(state, world, [&] { scorecard.observe_step(world); });
}
BENCHMARK(BM_ScoredStep)->Arg(0)->Arg(1);

// The telemetry snapshot a planner gets each cycle (with wire rounding).
void BM_Telemetry(benchmark::State& state) {
  const auto& track = default_track();
  sim::World world(track.map, track.line, run::default_config().world,
                   sim::TrafficProfile::faithful, 1);
  world.apply_path(lane_path(world, 1600));
  for (int i = 0; i < 1500; ++i) world.step();  // 30 s: every car placed
  world.apply_path(lane_path(world, 50));
  for (auto _ : state) benchmark::DoNotOptimize(world.telemetry());
}
BENCHMARK(BM_Telemetry);

// Projection of a point onto the reference line, with and without a hint.
void BM_ToFrenet(benchmark::State& state) {
  const auto& line = default_track().line;
  const bool hinted = state.range(0) != 0;
  double s = 100.0;
  for (auto _ : state) {
    const core::Vec2 p = line.to_cartesian({s, 6.0});
    benchmark::DoNotOptimize(hinted ? line.to_frenet(p, s - 0.4) : line.to_frenet(p));
    s += 7.3;
    if (s > line.length_m()) s -= line.length_m();
  }
  state.SetLabel(hinted ? "hinted" : "global");
}
BENCHMARK(BM_ToFrenet)->Arg(1)->Arg(0);

// One walkthrough planning cycle on a live telemetry.
void BM_WalkthroughPlan(benchmark::State& state) {
  const auto& track = default_track();
  const run::Config config = run::default_config();
  sim::World world(track.map, track.line, config.world, sim::TrafficProfile::faithful, 1);
  auto policy = planner::make_policy("walkthrough", track.line, config.planner);
  for (int i = 0; i < 500; ++i) {  // get up to speed so that the path is reused
    world.apply_path(policy->plan(world.telemetry()).path);
    world.step();
    world.step();
  }
  const core::Telemetry t = world.telemetry();
  for (auto _ : state) benchmark::DoNotOptimize(policy->plan(t));
}
BENCHMARK(BM_WalkthroughPlan);

// A whole 30-minute drive with the walkthrough policy: wall time and ratio to real time.
void BM_Drive30Minutes(benchmark::State& state) {
  run::DriveOptions o;
  o.minutes = 30.0;
  o.traffic = state.range(0) == 0 ? "faithful" : "calm";
  double simulated_s = 0.0;
  for (auto _ : state) {
    const auto r = run::drive(o);
    simulated_s += r.report.duration_s;
  }
  state.counters["x_real_time"] = benchmark::Counter(simulated_s, benchmark::Counter::kIsRate);
  state.SetLabel(o.traffic);
}
BENCHMARK(BM_Drive30Minutes)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(1);

// Resident memory of the process now (VmRSS, bytes); 0 where /proc is not there.
double resident_bytes() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "VmRSS:") {
      double kb = 0.0;
      status >> kb;
      return kb * 1024.0;
    }
    status.ignore(1 << 12, '\n');
  }
  return 0.0;
}

// Memory of a long drive (reference policy, faithful traffic): resident memory after the first
// 10 simulated seconds and at the end. Nothing in a run grows with its length (timing is
// kept in a fixed-size sketch), so a 4-hour drive ends where a 10-minute one does.
void BM_DriveMemory(benchmark::State& state) {
  run::DriveOptions o;
  o.minutes = static_cast<double>(state.range(0));
  double first = 0.0;
  double last = 0.0;
  for (auto _ : state) {
    first = 0.0;
    const auto r = run::drive(o, [&](double, double) {
      last = resident_bytes();
      if (first == 0.0) first = last;
    });
    benchmark::DoNotOptimize(r.report.duration_s);
    last = resident_bytes();
  }
  state.counters["rss_after_10s_MB"] = first / 1e6;
  state.counters["rss_at_end_MB"] = last / 1e6;
  state.counters["growth_kB"] = (last - first) / 1e3;
  state.SetLabel(std::to_string(state.range(0)) + " min");
}
BENCHMARK(BM_DriveMemory)->Arg(10)->Arg(240)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
