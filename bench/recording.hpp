#pragma once
// What the planner benchmarks share: the built-in track, the default config, and a drive
// recorded as the telemetry of each cycle (replayed in order through the policy under test).

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "overtake/core/random.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/sim/world.hpp"

namespace overtake::benchmarks {

inline const run::Track& track() {
  static const auto t = run::load_track(std::nullopt);
  return *t;
}

inline const run::Config& config() {
  static const run::Config c = run::default_config();
  return c;
}

/// The telemetry of every cycle of `seconds` of a drive by the built-in `policy` on the
/// built-in track, K steps per reply drawn from the configured range by `latency_seed`.
inline std::vector<core::Telemetry> record_drive(const std::string& policy_name,
                                                 sim::TrafficProfile profile, std::uint64_t seed,
                                                 std::uint64_t latency_seed, double seconds) {
  std::vector<core::Telemetry> rec;
  sim::World world(track().map, track().line, config().world, profile, seed);
  auto policy = planner::make_policy(policy_name, track().line, config().planner);
  core::Rng latency(latency_seed);
  const long steps = std::lround(seconds / config().world.step_s);
  while (world.steps() < steps) {
    rec.push_back(world.telemetry());
    world.apply_path(policy->plan(rec.back()).path);
    const int k =
        latency.uniform_int(config().world.min_steps_per_call, config().world.max_steps_per_call);
    for (int i = 0; i < k; ++i) world.step();
  }
  return rec;
}

}  // namespace overtake::benchmarks
