// World checkpoints (in replays and cut scenarios): sim::decode_checkpoint, then restoring
// what it read into a world of its traffic on the built-in track (the world, the scorecard
// and the stepper, then a few steps), and the reference policy's state; and recorded traffic
// (a replayed cut's cars): sim::decode_recorded_traffic, then a world following it; and a cut's
// warm-up (what a planner from outside was told): sim::decode_warm_up, then played to a planner
// that answers each telemetry's queued path. The first byte chooses which. Bad bytes are refused
// with core::StateError naming the part and the field; anything else (a crash, a sanitizer report,
// an index out of range) is a finding.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string_view>

#include "overtake/core/map.hpp"
#include "overtake/core/reference_line.hpp"
#include "overtake/core/state_archive.hpp"
#include "overtake/planner/params.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/run/resources.hpp"
#include "overtake/sim/checkpoint.hpp"
#include "overtake/sim/params.hpp"
#include "overtake/sim/recorded_traffic.hpp"
#include "overtake/sim/run.hpp"
#include "overtake/sim/warm_up.hpp"
#include "overtake/sim/world.hpp"

namespace {

using namespace overtake;

struct Track {
  core::Map map;
  core::ReferenceLine line;
};

const Track& track() {
  static const Track t = [] {
    core::Map m = core::parse_map(*resources::embedded_file("tracks/default.csv"), "default");
    core::ReferenceLine l(m);
    return Track{std::move(m), std::move(l)};
  }();
  return t;
}

void restore_run(const sim::Checkpoint& c) {
  const Track& t = track();
  const auto profile = sim::parse_traffic_profile(c.info.traffic);
  if (!profile) return;
  sim::World world(t.map, t.line, sim::WorldParams{}, *profile, c.info.seed);
  sim::RunOptions opts;
  opts.restore = c.run;
  opts.steps_per_call = 1;
  sim::Stepper run(world, opts);
  for (int i = 0; i < 5 && !run.finished(); ++i) run.step();
  (void)run.report();
  auto policy = planner::make_policy("reference", t.line, planner::PlannerParams{});
  if (planner::restore_policy_state(*policy, c.planner)) (void)policy->plan(world.telemetry());
}

void replay_cars(std::string_view bytes) {
  const Track& t = track();
  const sim::WorldParams params;
  sim::RecordedTraffic cars =
      sim::decode_recorded_traffic(bytes, "fuzz", params.road.lane_count, t.map.waypoints.size());
  sim::World world(t.map, t.line, params, sim::TrafficProfile::faithful, 1);
  world.replay_traffic(std::move(cars));
  for (int i = 0; i < 5; ++i) world.step();
  (void)world.telemetry();
}

void play(std::string_view bytes) {
  const sim::WarmUp w = sim::decode_warm_up(bytes, "fuzz");
  sim::WarmUpResult r;
  sim::play_warm_up(
      w, [](const core::Telemetry& t) { return core::normal_plan(t.previous_path); }, nullptr, r);
  (void)sim::first_disagreement(r, r);
  (void)sim::encode_warm_up(w);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    if (data[0] & 2U) {
      play(bytes);
    } else if (data[0] & 1U) {
      replay_cars(bytes);
    } else {
      restore_run(sim::decode_checkpoint(bytes, "fuzz"));
    }
  } catch (const core::StateError&) {
  }
  return 0;
}
