// The state archive and checkpoint files: values go through bit for bit, and bytes that do
// not hold a valid state are refused with a StateError naming the part and the field, never
// read as an out-of-range index, an absurd length or a value no run holds.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "overtake/core/reference_line.hpp"
#include "overtake/core/state_archive.hpp"
#include "overtake/sim/checkpoint.hpp"
#include "overtake/sim/faithful_traffic.hpp"
#include "overtake/sim/recorded_traffic.hpp"
#include "overtake/sim/run.hpp"
#include "overtake/sim/world.hpp"
#include "test_maps.hpp"

namespace overtake::sim {
namespace {

using ::testing::HasSubstr;

std::string error_of(std::string_view bytes, const std::function<void(core::StateArchive&)>& read) {
  try {
    core::StateArchive ar(bytes, "bytes");
    read(ar);
    ar.expect_end();
  } catch (const core::StateError& e) {
    return e.what();
  }
  return "";
}

TEST(StateArchive, EveryKindOfValueGoesThroughBitForBit) {
  core::StateArchive w;
  bool b = true;
  std::int32_t i = -7;
  std::int64_t l = -1234567890123;
  std::uint64_t u = 0xFEDCBA9876543210ULL;
  double d = 0.1 + 0.2;
  double inf = std::numeric_limits<double>::infinity();
  core::Vec2 v{1.5, -2.25};
  std::string text = "reason";
  std::optional<int> some = 4;
  std::vector<double> xs = {1.0, 1.0 + 1e-15, 2.0};
  core::Rng rng(42);
  (void)rng.next();
  std::uint64_t prev = 0;
  double series = 123.456;
  w.part("all");
  w.io(b, "b");
  w.io(i, "i");
  w.io(l, "l");
  w.io(u, "u");
  w.io(d, "d");
  w.io(inf, "inf");
  w.io(v, "v");
  w.io(text, 100, "text");
  w.io_optional(some, "some", [](core::StateArchive& a, int& x) { a.io(x, "x"); });
  w.io_vector(xs, 10, "xs");
  w.io(rng, "rng");
  w.io_delta(series, prev, "series");
  const std::string bytes = w.take();

  core::StateArchive r(bytes, "bytes");
  bool b2 = false;
  std::int32_t i2 = 0;
  std::int64_t l2 = 0;
  std::uint64_t u2 = 0;
  double d2 = 0, inf2 = 0, series2 = 0;
  core::Vec2 v2;
  std::string text2;
  std::optional<int> some2;
  std::vector<double> xs2;
  core::Rng rng2(0);
  std::uint64_t prev2 = 0;
  r.part("all");
  r.io(b2, "b");
  r.io(i2, "i");
  r.io(l2, "l");
  r.io(u2, "u");
  r.io(d2, "d");
  r.io(inf2, "inf");
  r.io(v2, "v");
  r.io(text2, 100, "text");
  r.io_optional(some2, "some", [](core::StateArchive& a, int& x) { a.io(x, "x"); });
  r.io_vector(xs2, 10, "xs");
  r.io(rng2, "rng");
  r.io_delta(series2, prev2, "series");
  r.expect_end();
  EXPECT_EQ(b2, b);
  EXPECT_EQ(i2, i);
  EXPECT_EQ(l2, l);
  EXPECT_EQ(u2, u);
  EXPECT_EQ(std::bit_cast<std::uint64_t>(d2), std::bit_cast<std::uint64_t>(d));
  EXPECT_EQ(inf2, inf);
  EXPECT_EQ(v2, v);
  EXPECT_EQ(text2, text);
  EXPECT_EQ(some2, some);
  EXPECT_EQ(xs2, xs);
  EXPECT_EQ(rng2.next(), rng.next());
  EXPECT_EQ(series2, series);
}

TEST(StateArchive, BadBytesNameThePartAndTheField) {
  core::StateArchive w;
  w.part("traffic");
  std::int32_t lane = 5;
  w.io(lane, "lane");
  double nan = std::nan("");
  double huge = 1e15;
  const std::string lane_bytes = w.bytes();
  w.io(nan, "speed");
  const std::string nan_bytes = w.take();
  EXPECT_THAT(error_of(lane_bytes,
                       [](core::StateArchive& a) {
                         a.part("traffic");
                         std::int32_t l = 0;
                         a.io_range(l, 0, 2, "lane");
                       }),
              HasSubstr("bytes: in part 'traffic', at byte 12: lane: 5 is outside [0, 2]"));
  EXPECT_THAT(error_of(lane_bytes, [](core::StateArchive& a) { a.part("world"); }),
              HasSubstr("expected part 'world'"));
  EXPECT_THAT(error_of(lane_bytes.substr(0, 10),
                       [](core::StateArchive& a) {
                         a.part("traffic");
                         std::int32_t l = 0;
                         a.io(l, "lane");
                       }),
              HasSubstr("lane: the state ends early"));
  EXPECT_THAT(error_of(nan_bytes,
                       [](core::StateArchive& a) {
                         a.part("traffic");
                         std::int32_t l = 0;
                         double s = 0;
                         a.io(l, "lane");
                         a.io(s, "speed");
                       }),
              HasSubstr("speed"));
  core::StateArchive big;
  big.io(huge, "position");
  EXPECT_THAT(error_of(big.bytes(),
                       [](core::StateArchive& a) {
                         double x = 0;
                         a.io_metres(x, "position");
                       }),
              HasSubstr("position"));
  // A length beyond what the field may hold is refused before anything is allocated.
  core::StateArchive len;
  std::uint64_t n = 1ULL << 60U;
  len.io(n, "xs");
  EXPECT_THAT(error_of(len.bytes(),
                       [](core::StateArchive& a) {
                         std::vector<double> xs;
                         a.io_vector(xs, 100, "xs");
                       }),
              HasSubstr("xs (count)"));
  EXPECT_THAT(error_of(lane_bytes + "x",
                       [](core::StateArchive& a) {
                         a.part("traffic");
                         std::int32_t l = 0;
                         a.io(l, "lane");
                       }),
              HasSubstr("1 bytes left over"));
}

struct Fixture {
  core::Map map = test::circle_map();
  core::ReferenceLine line{map};
};

Checkpoint checkpoint_after(const Fixture& f, TrafficProfile profile, int steps) {
  World world(f.map, f.line, WorldParams{}, profile, 3);
  RunOptions opts;
  opts.steps_per_call = 1;
  Stepper run(world, opts);
  for (int k = 0; k < steps; ++k) run.step();
  Checkpoint c;
  c.info.step = world.steps();
  c.info.t_s = world.time_s();
  c.info.traffic = std::string(to_string(profile));
  c.run = run.save();
  return c;
}

TEST(CheckpointFile, EveryTruncationIsRefusedAndWholeBytesReadBack) {
  const Fixture f;
  const Checkpoint c = checkpoint_after(f, TrafficProfile::faithful, 50);
  const std::string bytes = encode_checkpoint(c);
  EXPECT_EQ(bytes.substr(0, 8), "OVTKCKPT");
  EXPECT_EQ(decode_checkpoint(bytes, "c"), c);
  for (std::size_t n = 0; n < bytes.size(); n += 7) {
    EXPECT_THROW((void)decode_checkpoint(std::string_view(bytes).substr(0, n), "c"),
                 core::StateError)
        << n;
  }
  std::string other = bytes;
  other[8] = 9;  // the version
  try {
    (void)decode_checkpoint(other, "c");
    FAIL();
  } catch (const core::StateError& e) {
    EXPECT_THAT(e.what(), HasSubstr("checkpoint version 9"));
  }
  EXPECT_THROW((void)decode_checkpoint("OVTKRPLY", "c"), core::StateError);
}

TEST(CheckpointFile, ARunStateRestoresOnlyIntoAWorldMadeTheSameWay) {
  const Fixture f;
  const Checkpoint c = checkpoint_after(f, TrafficProfile::calm, 30);
  WorldParams fewer;
  fewer.traffic.car_count = 5;
  World world(f.map, f.line, fewer, TrafficProfile::calm, 3);
  RunOptions opts;
  opts.restore = c.run;
  try {
    Stepper run(world, opts);
    FAIL();
  } catch (const core::StateError& e) {
    EXPECT_THAT(e.what(), HasSubstr("in part 'calm traffic'"));
    EXPECT_THAT(e.what(), HasSubstr("cars (count): 12 is outside [0, 5]"));
  }
  // Every truncation of the run's state is refused (nothing restores half a world), but the
  // one that ends where the contacts' part begins: that is a checkpoint of a build before it.
  const std::size_t contacts_at = c.run.rfind(std::string(1, '\x08') + "contacts");
  ASSERT_NE(contacts_at, std::string::npos);
  for (std::size_t n = 0; n < c.run.size(); n += 97) {
    World w(f.map, f.line, WorldParams{}, TrafficProfile::calm, 3);
    RunOptions o;
    const std::string part = c.run.substr(0, n);
    o.restore = part;
    if (part.empty() || n == contacts_at) continue;  // empty: nothing to restore
    EXPECT_THROW(Stepper(w, o), core::StateError) << n;
  }
}

// A checkpoint of a build before contacts (no part "contacts" after the stepper's) restores,
// whole, with no contact so far; one of today's restores its contacts, and the run goes on
// as the one that never stopped.
TEST(CheckpointFile, ACheckpointWithoutContactsRestoresAndOneWithContactsGoesOnExactly) {
  const Fixture f;
  // A scripted contact: the ego at 20 m/s runs into a car at 10 m/s 15 m ahead (t = 1 s) and
  // keeps pushing it; the checkpoint is taken 2 s in, in the middle of the contact.
  Scenario sc;
  sc.ego_s_m = 100.0;
  sc.ego_d_m = 6.0;
  sc.ego_speed_mps = 20.0;
  sc.cars = {{115.0, 1, 10.0}};
  const auto plan = [](World& world) {
    return [&world](const core::Telemetry& t) {
      core::PlanResult r;
      r.path = t.previous_path;
      const double step = world.params().step_s;
      const double t_end = world.time_s() + static_cast<double>(r.path.size()) * step;
      for (int k = 1; r.path.size() < 50; ++k) {
        r.path.push_back(world.line().to_cartesian({100.0 + 20.0 * (t_end + k * step), 6.0}));
      }
      return r;
    };
  };
  const auto run_for = [&](World& world, double seconds, const std::string& restore) {
    RunOptions o;
    o.steps_per_call = 1;
    o.duration_s = seconds;
    o.restore = restore;
    return run_drive(world, plan(world), o);
  };
  World whole(f.map, f.line, WorldParams{}, sc);
  const RunReport straight = run_for(whole, 4.0, "");
  ASSERT_EQ(straight.contacts.size(), 1U);
  ASSERT_GE(straight.incident_counts[0], 2);

  // The same run, its checkpoints kept (every 2 s: at 2 s, inside the contact).
  struct Keep final : RunObserver {
    void on_frame(const Frame& /*frame*/, std::span<const Incident> /*new*/) override {}
    void on_path(std::span<const core::Vec2> /*path*/) override {}
    void on_checkpoint(const Checkpoint& c) override { kept.push_back(c); }
    std::vector<Checkpoint> kept;
  } keep;
  World first(f.map, f.line, WorldParams{}, sc);
  RunOptions o;
  o.steps_per_call = 1;
  o.duration_s = 4.0;
  o.checkpoint_every_s = 2.0;
  o.observer = &keep;
  EXPECT_EQ(run_drive(first, plan(first), o).contacts, straight.contacts);
  ASSERT_GE(keep.kept.size(), 2U);
  const Checkpoint& mid = keep.kept[1];
  ASSERT_NEAR(mid.info.t_s, 2.0, 0.03);
  ASSERT_LT(straight.contacts.front().t_s, mid.info.t_s);
  ASSERT_GT(straight.contacts.front().end_t_s, mid.info.t_s);
  const std::string state = mid.run;
  // Today's checkpoint: the contact goes on; the report is the straight run's.
  World again(f.map, f.line, WorldParams{}, sc);
  const RunReport resumed = run_for(again, 2.0, state);
  EXPECT_EQ(resumed.contacts, straight.contacts);
  EXPECT_EQ(resumed.incidents, straight.incidents);
  // Without the contacts' part: it restores; the contact open at the checkpoint is counted
  // anew from its next touch, and the earlier incidents keep their class but no contact.
  const std::size_t at = state.rfind(std::string(1, '\x08') + "contacts");
  ASSERT_NE(at, std::string::npos);
  World older(f.map, f.line, WorldParams{}, sc);
  const RunReport old = run_for(older, 2.0, state.substr(0, at));
  EXPECT_EQ(old.incident_counts, straight.incident_counts);
  EXPECT_EQ(old.contacts.size(), 1U);
  EXPECT_EQ(old.incidents.front().contact, -1);
}

// A run's state that says its traffic has run for longer than any run does is refused: catching
// the cars' wander up to it would take as long as that run (a state made to hang a restore).
TEST(CheckpointFile, ATrafficTimeBeyondAnyRunIsRefused) {
  const Fixture f;
  World world(f.map, f.line, WorldParams{}, TrafficProfile::faithful, 3);
  RunOptions opts;
  opts.steps_per_call = 1;
  Stepper run(world, opts);
  for (int k = 0; k < 137; ++k) run.step();
  const auto* traffic = dynamic_cast<const FaithfulTraffic*>(&world.traffic().model());
  ASSERT_NE(traffic, nullptr);
  const std::string state = run.save();
  // The traffic's clock is its last field, just before the referee's part begins.
  const double t = traffic->time_s();
  std::string bits(sizeof t, '\0');
  std::memcpy(bits.data(), &t, sizeof t);
  const std::size_t referee = state.find("\x07referee");
  ASSERT_NE(referee, std::string::npos);
  const std::size_t at = referee - sizeof t;
  ASSERT_EQ(state.substr(at, sizeof t), bits);
  for (const double bad : {1e9, -1.0, std::numeric_limits<double>::infinity()}) {
    std::string tampered = state;
    std::memcpy(tampered.data() + at, &bad, sizeof bad);
    World w(f.map, f.line, WorldParams{}, TrafficProfile::faithful, 3);
    RunOptions o;
    o.restore = tampered;
    try {
      Stepper(w, o);
      ADD_FAILURE() << "a traffic time of " << bad << " s restored";
    } catch (const core::StateError& e) {
      EXPECT_THAT(e.what(), HasSubstr("in part 'faithful traffic'"));
      EXPECT_THAT(e.what(), HasSubstr("time: "));
      EXPECT_THAT(e.what(), HasSubstr("is outside [0, 1e+06] s"));
    }
  }
}

TEST(RecordedTraffic, GoesThroughExactlyAndIsCheckedAgainstTheRoad) {
  const Fixture f;
  World world(f.map, f.line, WorldParams{}, TrafficProfile::faithful, 5);
  RecordedTraffic steps;
  for (int k = 0; k < 200; ++k) {
    world.step();
    steps.push_back(world.traffic().cars());
  }
  const std::string bytes = encode_recorded_traffic(steps);
  const RecordedTraffic back = decode_recorded_traffic(bytes, "r", 3, f.map.waypoints.size());
  ASSERT_EQ(back.size(), steps.size());
  for (std::size_t k = 0; k < steps.size(); ++k) {
    ASSERT_EQ(back[k].size(), steps[k].size());
    for (std::size_t i = 0; i < steps[k].size(); ++i) {
      EXPECT_EQ(back[k][i].position, steps[k][i].position);
      EXPECT_EQ(back[k][i].speed_mps, steps[k][i].speed_mps);
      EXPECT_EQ(back[k][i].map_frenet, steps[k][i].map_frenet);
      EXPECT_EQ(back[k][i].parked, steps[k][i].parked);
    }
  }
  // On a road of one lane, lane 2 is refused.
  EXPECT_THROW((void)decode_recorded_traffic(bytes, "r", 1, f.map.waypoints.size()),
               core::StateError);
}

}  // namespace
}  // namespace overtake::sim

namespace overtake::sim {
namespace {

// The traffic's bodies after `steps` more steps of a run restored from `state` (reseeded
// when asked): where every car is.
std::vector<core::Vec2> cars_after(const Fixture& f, const std::string& state,
                                   std::optional<std::uint64_t> reseed, int steps,
                                   std::vector<core::Vec2>* at_start = nullptr) {
  World world(f.map, f.line, WorldParams{}, TrafficProfile::faithful, 3);
  RunOptions o;
  o.steps_per_call = 1;
  o.restore = state;
  o.reseed = reseed;
  Stepper run(world, o);
  const auto bodies = [&world] {
    std::vector<core::Vec2> out;
    for (const TrafficCar& c : world.traffic().cars()) out.push_back(c.position);
    return out;
  };
  if (at_start) *at_start = bodies();
  for (int k = 0; k < steps; ++k) run.step();
  return bodies();
}

bool same(const std::vector<core::Vec2>& a, const std::vector<core::Vec2>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].x != b[i].x || a[i].y != b[i].y) return false;
  }
  return true;
}

TEST(CheckpointReseed, ABranchIsTheSameWorldWithNewDrawsAndTheSameSeedGivesTheSameBranch) {
  const Fixture f;
  const Checkpoint c = checkpoint_after(f, TrafficProfile::faithful, 1500);
  const int later = 3000;  // a minute: spawns and the wander's lattice draw again in it
  std::vector<core::Vec2> start_plain, start_branch;
  const auto plain = cars_after(f, c.run, std::nullopt, later, &start_plain);
  // Without a reseed the run goes on as it would have: twice the same.
  EXPECT_TRUE(same(plain, cars_after(f, c.run, std::nullopt, later)));
  // A branch starts from the same bodies ...
  const auto branch = cars_after(f, c.run, 11, later, &start_branch);
  EXPECT_TRUE(same(start_plain, start_branch));
  // ... draws anew from there (another world a minute on) ...
  EXPECT_FALSE(same(plain, branch));
  EXPECT_FALSE(same(branch, cars_after(f, c.run, 12, later)));
  // ... and is the same branch for the same seed.
  EXPECT_TRUE(same(branch, cars_after(f, c.run, 11, later)));
}

}  // namespace
}  // namespace overtake::sim
