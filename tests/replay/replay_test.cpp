// Replay files: write -> read round trips (fixed-point fields bit for bit, positions coded as
// differences: cars coming and going, far jumps), the writer's temporary file and rename, and
// clear errors for damaged files (every cut of a record, values out of range).

#include "overtake/replay/replay.hpp"

#include "overtake/core/telemetry.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "overtake/core/units.hpp"
#include "overtake/sim/run.hpp"
#include "overtake/sim/scorecard.hpp"
#include "overtake/sim/world.hpp"
#include "sim/test_maps.hpp"
#include "zlib_support.hpp"

namespace overtake::replay {
namespace {

using namespace sim;

using ::testing::AllOf;
using ::testing::HasSubstr;

constexpr double kCruiseMps = 24.0;  // above the 50 mph limit: speeding incidents
constexpr double kLaneD = 6.0;
constexpr const char* kReport = R"({"distance_miles":1.5,"ended_early":null})";

// Every frame and path the run showed its watchers, exactly, to compare with the file.
class Capture final : public RunObserver {
 public:
  void on_frame(const Frame& f, std::span<const Incident>) override { states.push_back(f); }
  void on_path(std::span<const core::Vec2> path) override {
    paths.emplace_back(path.begin(), path.end());
    path_steps.push_back(states.empty() ? -1 : states.back().step);
  }
  std::vector<Frame> states;
  std::vector<std::vector<core::Vec2>> paths;
  std::vector<long> path_steps;
};

// The frame of a world before its first step, as a run's watchers see it.
Frame first_frame(const World& world) {
  const Scorecard card(world);
  Frame f;
  card.fill_frame(world, f);
  return f;
}

long long cm(double m) {
  return std::llround(m * 100.0);
}
long long yaw_units(double rad) {
  return std::llround(core::wrap_angle_rad(rad) * 1e4);
}
float f32(double v) {
  return static_cast<float>(v);
}

std::string read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

// The header length field of a replay's preamble.
std::size_t r_header_bytes(const std::string& bytes) {
  std::size_t n = 0;
  for (int i = 0; i < 4; ++i)
    n |= static_cast<std::size_t>(static_cast<unsigned char>(bytes[12 + i])) << (8 * i);
  return n;
}

void write_bytes(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

class ReplayTest : public ::testing::Test {
 protected:
  ReplayTest() : map_(test::circle_map()), line_(map_) {
    dir_ = std::filesystem::temp_directory_path() /
           ("overtake_replay_test_" +
            std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  ~ReplayTest() override { std::filesystem::remove_all(dir_); }

  ReplayHeader header() const {
    ReplayProvenance p;
    p.policy = "test-cruise";
    p.traffic = "faithful";
    p.seed = 5;
    p.track = "test:circle";
    p.duration_s = 20.0;
    p.overtake_version = "test";
    p.config_hash = "0123456789abcdef";
    return make_replay_header(line_, params_, p);
  }

  // Cruises lane 1 at kCruiseMps from a standing start: speeding and acceleration incidents.
  PlannerFn cruise() const {
    return [this](const core::Telemetry& t) {
      std::vector<core::Vec2> path;
      for (int i = 1; i <= 50; ++i) {
        path.push_back(line_.to_cartesian({t.ego.s_m + kCruiseMps * params_.step_s * i, kLaneD}));
      }
      return core::normal_plan(std::move(path));
    };
  }

  // Records a run of `seconds` into `file`; returns what the capture saw.
  Capture record(const std::filesystem::path& file, double seconds, std::uint64_t seed = 5) {
    World world(map_, line_, params_, TrafficProfile::faithful, seed);
    ReplayWriter writer(file, header());
    Capture capture;
    ObserverList both({&writer, &capture});
    RunOptions opts;
    opts.duration_s = seconds;
    opts.seed = seed;
    opts.observer = both.get();
    report_ = run_drive(world, cruise(), opts);
    writer.finish(kReport);
    return capture;
  }

  core::Map map_;
  core::ReferenceLine line_;
  WorldParams params_;
  RunReport report_;
  std::filesystem::path dir_;
};

TEST_F(ReplayTest, RoundTripKeepsEveryFieldBitForBit) {
  const auto file = dir_ / "run.otr";
  const Capture seen = record(file, 20.0);
  const Replay r = read_replay(file);

  // Header.
  const ReplayHeader h = header();
  EXPECT_EQ(r.header.provenance, h.provenance);
  EXPECT_DOUBLE_EQ(r.header.step_s, 0.02);
  EXPECT_EQ(r.header.lanes, 3);
  EXPECT_DOUBLE_EQ(r.header.track_length_m, line_.length_m());
  EXPECT_DOUBLE_EQ(r.header.speed_limit_mps, params_.referee.speed_limit_mps);
  ASSERT_EQ(r.header.lane_lines.size(), 4u);
  for (const auto& l : r.header.lane_lines) {
    ASSERT_GE(l.size(), 4u);
    EXPECT_EQ(l[0], l[l.size() - 2]);  // closed
    EXPECT_EQ(l[1], l[l.size() - 1]);
    EXPECT_LE(2.0 * line_.length_m() / kReplayLaneLineSpacingM, static_cast<double>(l.size()));
  }
  EXPECT_EQ(r.header.incident_types.size(), kIncidentTypeCount);
  EXPECT_EQ(r.header.incident_types[1], "speeding");
  ASSERT_EQ(r.header.collision_kinds.size(), kCollisionKindCount);
  EXPECT_EQ(r.header.collision_kinds[1], "hit_from_behind");
  EXPECT_EQ(r.end_json, kReport);
  EXPECT_EQ(r.unknown_records, 0u);

  // Frames: step 0 and every step after it.
  ASSERT_EQ(r.frames.size(), seen.states.size());
  ASSERT_EQ(r.frames.size(), 1001u);
  for (std::size_t i = 0; i < r.frames.size(); ++i) {
    const ReplayFrame& f = r.frames[i];
    const Frame& s = seen.states[i];
    SCOPED_TRACE("frame " + std::to_string(i));
    ASSERT_EQ(f.step, s.step);
    EXPECT_EQ(cm(f.position.x), cm(s.position.x));
    EXPECT_EQ(cm(f.position.y), cm(s.position.y));
    EXPECT_EQ(std::llround(f.yaw_rad * 1e4), yaw_units(s.yaw_rad));
    EXPECT_EQ(std::llround(f.speed_mps * 100.0), cm(s.speed_mps));
    EXPECT_EQ(f32(f.s_m), f32(s.s_m));
    EXPECT_EQ(f32(f.d_m), f32(s.d_m));
    EXPECT_EQ(f32(f.strict.tangential_mps2), f32(s.strict.tangential_mps2));
    EXPECT_EQ(f32(f.strict.normal_mps2), f32(s.strict.normal_mps2));
    EXPECT_EQ(f32(f.strict.acceleration_mps2), f32(s.strict.acceleration_mps2));
    EXPECT_EQ(f32(f.strict.jerk_mps3), f32(s.strict.jerk_mps3));
    EXPECT_EQ(f32(f.distance_m), f32(s.distance_m));
    EXPECT_EQ(f32(f.incident_free_m), f32(s.incident_free_m));
    EXPECT_EQ(f32(f.best_incident_free_m), f32(s.best_incident_free_m));
    // TTC and headway in hundredths of a second; none (infinity) stays none.
    const auto cs = [](double v) { return v < 655.35 ? std::llround(v * 100.0) : 65535LL; };
    EXPECT_EQ(cs(f.safety.ttc_ahead_s), cs(s.safety.ttc_ahead_s));
    EXPECT_EQ(cs(f.safety.ttc_entering_s), cs(s.safety.ttc_entering_s));
    EXPECT_EQ(cs(f.safety.headway_s), cs(s.safety.headway_s));
    EXPECT_EQ(std::isinf(f.safety.headway_s), std::isinf(s.safety.headway_s));
    ASSERT_EQ(f.cars.size(), s.cars.size());
    for (std::size_t c = 0; c < f.cars.size(); ++c) {
      EXPECT_EQ(f.cars[c].id, s.cars[c].id);
      EXPECT_EQ(cm(f.cars[c].position.x), cm(s.cars[c].position.x));
      EXPECT_EQ(cm(f.cars[c].position.y), cm(s.cars[c].position.y));
      EXPECT_EQ(std::llround(f.cars[c].yaw_rad * 1e4), yaw_units(s.cars[c].yaw_rad));
      EXPECT_EQ(std::llround(f.cars[c].speed_mps * 100.0), cm(s.cars[c].speed_mps));
    }
  }
  EXPECT_EQ(r.frames.front().step, 0);
  EXPECT_EQ(r.frames.front().strict, StrictFigures{});

  // Paths: one per planner cycle, each after the frame it was planned from.
  ASSERT_EQ(r.paths.size(), seen.paths.size());
  EXPECT_EQ(static_cast<long>(r.paths.size()), report_.planner_cycles);
  for (std::size_t i = 0; i < r.paths.size(); ++i) {
    EXPECT_EQ(r.paths[i].step, seen.path_steps[i]);
    ASSERT_EQ(r.paths[i].points.size(), seen.paths[i].size());
    for (std::size_t k = 0; k < r.paths[i].points.size(); ++k) {
      EXPECT_EQ(cm(r.paths[i].points[k].x), cm(seen.paths[i][k].x));
      EXPECT_EQ(cm(r.paths[i].points[k].y), cm(seen.paths[i][k].y));
    }
  }

  // Incidents: the referee's, at the frame of their time, values as in the report.
  ASSERT_FALSE(report_.incidents.empty());
  ASSERT_EQ(r.incidents.size(), report_.incidents.size());
  for (std::size_t i = 0; i < r.incidents.size(); ++i) {
    const Incident& want = report_.incidents[i];
    const ReplayIncident& got = r.incidents[i];
    EXPECT_EQ(got.type, static_cast<int>(want.type));
    EXPECT_EQ(got.step, std::lround(want.t_s / 0.02));
    const double value =
        want.type == IncidentType::speeding ? core::mps_to_mph(want.value) : want.value;
    EXPECT_EQ(f32(got.value), f32(value));
    EXPECT_EQ(f32(got.s_m), f32(want.s_m));
    EXPECT_EQ(got.lane, want.lane);
    const auto at = static_cast<std::size_t>(got.step);
    EXPECT_EQ(cm(got.position.x), cm(seen.states[at].position.x));
    EXPECT_EQ(got.collision, want.collision);
    EXPECT_EQ(got.contact, want.type == IncidentType::collision ? want.contact : -1);
  }
  // Some frames had a car ahead, so the figures were measured.
  EXPECT_TRUE(std::any_of(r.frames.begin(), r.frames.end(),
                          [](const ReplayFrame& f) { return std::isfinite(f.safety.headway_s); }));
}

// A run of a planner from outside keeps each path as the world reads it, bit for bit (overtake
// cut drives the world on with them): as whole 1e-4 m where they are, as their bits where one
// is not (a coordinate of a few micrometres); other runs keep centimetres only.
TEST_F(ReplayTest, ExactPathsComeBackBitForBitWhenAsked) {
  const auto file = dir_ / "exact.otr";
  World world(map_, line_, params_, TrafficProfile::faithful, 5);
  ReplayWriter writer(file, header());
  writer.set_exact_paths(true);
  std::vector<std::vector<core::Vec2>> sent;
  RunOptions opts;
  opts.duration_s = 3.0;
  opts.observer = &writer;
  (void)run_drive(
      world,
      [&](const core::Telemetry& t) {
        core::PlanResult r = cruise()(t);
        r.path.front().x += 1e-3 * static_cast<double>(sent.size() % 7);  // below a centimetre
        if (sent.size() == 5) r.path.back() = {1.234567e-5, -9.87654321e-4};
        sent.push_back(core::round_like_wire(r.path));
        return r;
      },
      opts);
  writer.finish(kReport);
  const Replay r = read_replay(file);
  ASSERT_EQ(r.paths.size(), sent.size());
  for (std::size_t k = 0; k < sent.size(); ++k) {
    ASSERT_TRUE(r.paths[k].has_exact);
    EXPECT_EQ(r.paths[k].exact, sent[k]) << "path " << k;
  }
  record(dir_ / "plain.otr", 3.0);
  for (const ReplayPath& p : read_replay(dir_ / "plain.otr").paths) {
    EXPECT_FALSE(p.has_exact);
    EXPECT_TRUE(p.exact.empty());
  }
}

TEST_F(ReplayTest, ChecksAReplayWithoutKeepingIt) {
  const auto file = dir_ / "run.otr";
  (void)record(file, 5.0);
  const ReplayCheck c = check_replay(read_bytes(file), file.string());
  EXPECT_EQ(c.error, "");
  EXPECT_EQ(c.frames, 251u);
  EXPECT_DOUBLE_EQ(c.duration_s, 5.0);
  EXPECT_GT(c.records, c.frames);
}

TEST_F(ReplayTest, SameRunGivesTheSameBytes) {
  (void)record(dir_ / "a.otr", 10.0, 9);
  (void)record(dir_ / "b.otr", 10.0, 9);
  const std::string a = read_bytes(dir_ / "a.otr");
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, read_bytes(dir_ / "b.otr"));
}

TEST_F(ReplayTest, WritesAPartialFileAndRenamesItAtTheEnd) {
  const auto file = dir_ / "run.otr";
  World world(map_, line_, params_, TrafficProfile::faithful, 1);
  ReplayWriter writer(file, header());
  RunOptions opts;
  opts.duration_s = 2.0;
  opts.observer = &writer;
  (void)run_drive(world, cruise(), opts);
  EXPECT_FALSE(std::filesystem::exists(file));
  EXPECT_TRUE(std::filesystem::exists(writer.partial_path()));
  writer.finish(kReport);
  EXPECT_TRUE(std::filesystem::exists(file));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "run.otr.partial"));
  EXPECT_EQ(writer.bytes_written(), std::filesystem::file_size(file));
  EXPECT_THROW(writer.finish(kReport), ReplayError);
}

TEST_F(ReplayTest, AnEarlierKilledRunsPartialFileIsKept) {
  const auto file = dir_ / "run.otr";
  {
    std::ofstream stale(dir_ / "run.otr.partial", std::ios::binary);
    stale << "an earlier run's records";
  }
  World world(map_, line_, params_, TrafficProfile::faithful, 1);
  ReplayWriter writer(file, header());
  EXPECT_EQ(writer.partial_path(), dir_ / "run.otr.1.partial");
  RunOptions opts;
  opts.duration_s = 1.0;
  opts.observer = &writer;
  (void)run_drive(world, cruise(), opts);
  writer.finish(kReport);
  EXPECT_EQ(read_bytes(dir_ / "run.otr.partial"), "an earlier run's records");
  EXPECT_FALSE(std::filesystem::exists(dir_ / "run.otr.1.partial"));
  EXPECT_EQ(read_replay(file).frames.size(), 51u);
}

TEST_F(ReplayTest, TwoRecordingsToOneFileAtOnceLeaveAWholeReplay) {
  // Interleaved as two processes would: each writes its own partial file; whichever renames
  // last, the file holds one whole replay.
  const auto file = dir_ / "run.otr";
  World a(map_, line_, params_, TrafficProfile::faithful, 1);
  World b(map_, line_, params_, TrafficProfile::faithful, 2);
  ReplayWriter wa(file, header());
  ReplayWriter wb(file, header());
  EXPECT_NE(wa.partial_path(), wb.partial_path());
  RunOptions oa;
  oa.duration_s = 2.0;
  oa.observer = &wa;
  RunOptions ob = oa;
  ob.observer = &wb;
  (void)run_drive(a, cruise(), oa);
  (void)run_drive(b, cruise(), ob);
  wa.finish(kReport);
  EXPECT_EQ(read_replay(file).frames.size(), 101u);
  wb.finish(kReport);
  EXPECT_EQ(read_replay(file).frames.size(), 101u);
  EXPECT_EQ(read_bytes(file).size(), wb.bytes_written());
}

TEST_F(ReplayTest, AnUnfinishedRecordingIsEndedProperly) {
  const auto file = dir_ / "run.otr";
  {
    World world(map_, line_, params_, TrafficProfile::faithful, 1);
    ReplayWriter writer(file, header());
    RunOptions opts;
    opts.duration_s = 3.0;
    opts.observer = &writer;
    (void)run_drive(world, cruise(), opts);
  }  // no finish(): as when the run throws
  const Replay r = read_replay(file);
  EXPECT_EQ(r.frames.size(), 151u);
  EXPECT_THAT(r.end_json, HasSubstr("ended_early"));
}

TEST_F(ReplayTest, AFailedRunKeepsItsRecordsAndReport) {
  const auto file = dir_ / "run.otr";
  World world(map_, line_, params_, TrafficProfile::faithful, 1);
  ReplayWriter writer(file, header());
  RunOptions opts;
  opts.duration_s = 10.0;
  opts.observer = &writer;
  int calls = 0;
  const PlannerFn inner = cruise();
  const RunReport rep = run_drive(
      world,
      [&](const core::Telemetry& t) {
        if (++calls > 100) throw PlannerFailure("stalled");
        return inner(t);
      },
      opts);
  ASSERT_EQ(rep.outcome.end, RunEnd::planner_failed);
  writer.finish(R"({"ended_early":"planner failed"})");
  const Replay r = read_replay(file);
  EXPECT_EQ(r.paths.size(), 100u);
  EXPECT_EQ(r.frames.back().step, world.steps());
}

TEST_F(ReplayTest, CannotCreateTheFileIsAClearError) {
  try {
    ReplayWriter writer(dir_ / "no-such-dir" / "run.otr", header());
    FAIL() << "expected ReplayError";
  } catch (const ReplayError& e) {
    EXPECT_THAT(e.what(), HasSubstr("no-such-dir/run.otr.partial"));
    EXPECT_THAT(e.what(), HasSubstr("cannot create"));
  }
}

std::string error_of(const std::filesystem::path& file) {
  try {
    (void)read_replay(file);
  } catch (const ReplayError& e) {
    return e.what();
  }
  return "";
}

TEST_F(ReplayTest, ATruncatedFileIsReportedWithItsNameAndWhere) {
  const auto file = dir_ / "run.otr";
  (void)record(file, 20.0);
  const std::string bytes = read_bytes(file);
  const auto cut = dir_ / "cut.otr";
  const std::size_t body = kReplayPreambleBytes + r_header_bytes(bytes);
  write_bytes(cut, bytes.substr(0, body + (bytes.size() - body) * 6 / 10));
  const std::string e = error_of(cut);
  EXPECT_THAT(e, HasSubstr(cut.string()));
  EXPECT_THAT(e, HasSubstr("truncated"));
  EXPECT_THAT(e, HasSubstr("after record #"));
  // The records before the cut are still readable.
  const ReplayCheck c = check_replay(read_bytes(cut), "cut.otr");
  EXPECT_THAT(c.error, HasSubstr("truncated"));
  EXPECT_GT(c.frames, 100u);

  write_bytes(cut, bytes.substr(0, 12));
  EXPECT_THAT(error_of(cut), HasSubstr("inside its 16-byte preamble"));
  write_bytes(cut, bytes.substr(0, 200));
  EXPECT_THAT(error_of(cut), HasSubstr("truncated: the header is"));
  const std::size_t header_end = kReplayPreambleBytes + r_header_bytes(bytes);
  write_bytes(cut, bytes.substr(0, header_end));
  EXPECT_THAT(error_of(cut), HasSubstr("with no records"));
}

TEST_F(ReplayTest, ACorruptedByteIsReported) {
  const auto file = dir_ / "run.otr";
  (void)record(file, 20.0);
  std::string bytes = read_bytes(file);
  const std::size_t header_end = kReplayPreambleBytes + r_header_bytes(bytes);
  const auto bad = dir_ / "bad.otr";
  // A byte in the middle of the compressed body: zlib finds it (bad code or checksum).
  std::string body = bytes;
  body[header_end + (bytes.size() - header_end) / 2] ^= 0x5a;
  write_bytes(bad, body);
  std::string e = error_of(bad);
  EXPECT_THAT(e, HasSubstr(bad.string()));
  EXPECT_THAT(e, HasSubstr("corrupt"));
  // The last byte (the checksum).
  body = bytes;
  body.back() ^= 0x01;
  write_bytes(bad, body);
  EXPECT_THAT(error_of(bad), HasSubstr("corrupt"));
  // A byte of the header's JSON.
  body = bytes;
  body[kReplayPreambleBytes] = '#';
  write_bytes(bad, body);
  EXPECT_THAT(error_of(bad), HasSubstr("corrupt header"));
  // Bytes after the end of the stream.
  write_bytes(bad, bytes + "xyz");
  EXPECT_THAT(error_of(bad), HasSubstr("3 unexpected bytes after the compressed body"));
}

TEST_F(ReplayTest, NotAReplayOrAnotherVersion) {
  const auto file = dir_ / "run.otr";
  (void)record(file, 1.0);
  std::string bytes = read_bytes(file);
  const auto bad = dir_ / "bad.otr";
  write_bytes(bad, "x y s dx dy\n1 2 3 4 5\n");
  EXPECT_THAT(error_of(bad), HasSubstr("not an overtake replay"));
  write_bytes(bad, "");
  EXPECT_THAT(error_of(bad), HasSubstr("empty"));
  bytes[8] = 1;
  write_bytes(bad, bytes);
  EXPECT_THAT(error_of(bad), HasSubstr("bad.otr: replay format version 1 is not supported"));
  EXPECT_THAT(error_of(bad), HasSubstr("re-record the run"));
  bytes[8] = 3;
  write_bytes(bad, bytes);
  EXPECT_THAT(error_of(bad), HasSubstr("version 3; this build reads version 2"));
  EXPECT_THAT(error_of(dir_ / "missing.otr"), HasSubstr("cannot open"));
}

// A file made by hand: the preamble of a real header and the given records.
std::string handmade(const ReplayHeader& h, const std::string& records) {
  return replay_preamble(h) + test::deflate_all(records);
}

constexpr std::size_t kRecordHead = 5;  // u8 kind, u32 length

std::string record_of(std::uint8_t kind, const std::string& payload) {
  std::string out(1, static_cast<char>(kind));
  const auto n = static_cast<std::uint32_t>(payload.size());
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((n >> (8 * i)) & 0xff));
  return out + payload;
}

TEST_F(ReplayTest, NoEndRecordIsTruncated) {
  World world(map_, line_, params_, TrafficProfile::faithful, 1);
  ReplayEncoder enc;
  std::string records;
  enc.append_frame(first_frame(world), records);
  const auto bad = dir_ / "bad.otr";
  write_bytes(bad, handmade(header(), records));
  const std::string e = error_of(bad);
  EXPECT_THAT(e, HasSubstr("no end record"));
  EXPECT_THAT(e, HasSubstr("after record #1 (step 0, t = 0.00 s)"));
}

TEST_F(ReplayTest, UnknownKindsAreSkippedAndBadRecordsNamed) {
  World world(map_, line_, params_, TrafficProfile::faithful, 1);
  ReplayEncoder enc;
  std::string records;
  enc.append_frame(first_frame(world), records);
  records += record_of(42, "future");
  ReplayEncoder::append_end("{}", records);
  const auto file = dir_ / "ok.otr";
  write_bytes(file, handmade(header(), records));
  const Replay r = read_replay(file);
  EXPECT_EQ(r.unknown_records, 1u);
  EXPECT_EQ(r.frames.size(), 1u);

  // A frame too short for its cars; a path before any frame; a second frame with the same step.
  std::string short_frame;
  ReplayEncoder fresh;
  fresh.append_frame(first_frame(world), short_frame);
  short_frame = record_of(1, short_frame.substr(5, 60));
  write_bytes(file, handmade(header(), short_frame));
  EXPECT_THAT(error_of(file), HasSubstr("record #1 (frame, at inflated byte 0): the ids of its 12 "
                                        "cars run past the end of the 60-byte payload"));
  std::string path_first;
  ReplayEncoder().append_path(std::vector<core::Vec2>{{1.0, 2.0}}, path_first);
  write_bytes(file, handmade(header(), path_first));
  EXPECT_THAT(error_of(file), HasSubstr("a path before the first frame"));
  std::string twice;
  ReplayEncoder e1, e2;
  e1.append_frame(first_frame(world), twice);
  e2.append_frame(first_frame(world), twice);
  write_bytes(file, handmade(header(), twice));
  EXPECT_THAT(error_of(file), HasSubstr("step 0 does not follow step 0"));
}

TEST_F(ReplayTest, AnIncidentsContactIsReadAndOneOnNoCollisionRefused) {
  World world(map_, line_, params_, TrafficProfile::faithful, 1);
  ReplayEncoder enc;
  std::string records;
  enc.append_frame(first_frame(world), records);
  Incident hit;
  hit.type = IncidentType::collision;
  hit.value = 4.0;
  hit.collision = CollisionClass{CollisionKind::ego_hit_car_ahead, true};
  hit.contact = 2;
  Incident speeding;
  speeding.type = IncidentType::speeding;
  speeding.value = 23.0;
  const std::vector<Incident> both = {hit, speeding};
  enc.append_incidents(both, records);
  std::string good = records;
  ReplayEncoder::append_end("{}", good);
  const auto file = dir_ / "contact.otr";
  write_bytes(file, handmade(header(), good));
  const Replay r = read_replay(file);
  ASSERT_EQ(r.incidents.size(), 2U);
  EXPECT_EQ(r.incidents[0].contact, 2);
  EXPECT_EQ(r.incidents[0].collision, hit.collision);
  EXPECT_EQ(r.incidents[1].contact, -1);
  // A 20-byte incident (a file from before contacts) has none.
  std::string older;
  ReplayEncoder().append_frame(first_frame(world), older);
  std::string one;
  enc.append_incidents(std::vector<Incident>{hit}, one);
  older += record_of(3, one.substr(5, 20));
  ReplayEncoder::append_end("{}", older);
  write_bytes(file, handmade(header(), older));
  EXPECT_EQ(read_replay(file).incidents.at(0).contact, -1);
  // A contact number on a speeding incident is refused.
  std::string bad;
  ReplayEncoder().append_frame(first_frame(world), bad);
  std::string payload = one.substr(5);
  payload[0] = static_cast<char>(IncidentType::speeding);
  bad += record_of(3, payload);
  ReplayEncoder::append_end("{}", bad);
  write_bytes(file, handmade(header(), bad));
  EXPECT_THAT(error_of(file), HasSubstr("a contact number on an incident that is no classified "
                                        "collision"));
}

// Found by fuzz/replay_fuzz.cpp (UBSan: 1e+300 is outside the range of int): the header's
// integers must be integers that fit, never truncated, wrapped or converted out of range.
TEST_F(ReplayTest, HeaderIntegersMustBeIntegersThatFit) {
  World world(map_, line_, params_, TrafficProfile::faithful, 1);
  std::string records;
  ReplayEncoder().append_frame(first_frame(world), records);
  ReplayEncoder::append_end("{}", records);
  const std::string good = replay_header_json(header());
  const auto file = dir_ / "bad.otr";
  // The error reading the file whose header has `from` replaced by `to`.
  const auto with = [&](const std::string& from, const std::string& to) {
    std::string text = good;
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
    std::string bytes(kReplayMagic);
    for (const std::uint32_t v : {kReplayVersion, static_cast<std::uint32_t>(text.size())}) {
      for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
    }
    write_bytes(file, bytes + text + test::deflate_all(records));
    return error_of(file);
  };
  EXPECT_EQ(with(R"("lanes":3)", R"("lanes":3)"), "");
  EXPECT_EQ(with(R"("seed":5)", R"("seed":18446744073709551615)"), "");
  EXPECT_THAT(with(R"("lanes":3)", R"("lanes":1e300)"), HasSubstr("corrupt header (bytes 16-"));
  EXPECT_THAT(with(R"("lanes":3)", R"("lanes":1e300)"),
              HasSubstr("'road.lanes' is 1e+300, not an integer within range"));
  EXPECT_THAT(with(R"("lanes":3)", R"("lanes":3.5)"),
              HasSubstr("'road.lanes' is 3.5, not an integer within range"));
  EXPECT_THAT(with(R"("lanes":3)", R"("lanes":4294967299)"),
              HasSubstr("'road.lanes' is 4294967299, not an integer within range"));
  EXPECT_THAT(with(R"("lanes":3)", R"("lanes":"3")"), HasSubstr("'road.lanes' is not an integer"));
  EXPECT_THAT(with(R"("seed":5)", R"("seed":-1)"),
              HasSubstr("'provenance.seed' is -1, not an integer within range"));
  EXPECT_THAT(with(R"("seed":5)", R"("seed":-1.5e300)"),
              HasSubstr("'provenance.seed' is -1.5e+300, not an integer within range"));
}

// A header nested 100,000 deep once overflowed the stack while its error was written.
TEST_F(ReplayTest, AHeaderNestedTooDeepIsCorruptNotACrash) {
  World world(map_, line_, params_, TrafficProfile::faithful, 1);
  std::string records;
  ReplayEncoder().append_frame(first_frame(world), records);
  ReplayEncoder::append_end("{}", records);
  std::string text = replay_header_json(header());
  const std::string from = R"("lanes":3)";
  text.replace(text.find(from), from.size(),
               R"("lanes":)" + std::string(100'000, '[') + std::string(100'000, ']'));
  std::string bytes(kReplayMagic);
  for (const std::uint32_t v : {kReplayVersion, static_cast<std::uint32_t>(text.size())}) {
    for (int i = 0; i < 4; ++i) bytes.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  }
  const auto file = dir_ / "deep.otr";
  write_bytes(file, bytes + text + test::deflate_all(records));
  EXPECT_THAT(error_of(file), AllOf(HasSubstr("corrupt header (bytes 16-"),
                                    HasSubstr("JSON nested deeper than 64 levels")));
}

// /dev/zero would be read until memory ran out, and a FIFO would wait for a writer forever.
TEST_F(ReplayTest, OnlyARegularFileIsRead) {
  EXPECT_THAT(error_of("/dev/zero"), HasSubstr("/dev/zero: not a regular file"));
  EXPECT_THAT(error_of(dir_), HasSubstr("not a regular file"));
  const auto fifo = dir_ / "fifo.otr";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THAT(error_of(fifo), HasSubstr("fifo.otr: not a regular file"));
}

// ---- positions as differences ---------------------------------------------------------------

ReplayCar car(int id, double x, double y, double yaw = 0.0, double speed = 10.0) {
  return {id, {x, y}, yaw, speed};
}

ReplayFrame frame_at(long step, double x, double y, std::vector<ReplayCar> cars) {
  ReplayFrame f;
  f.step = step;
  f.position = {x, y};
  f.yaw_rad = 0.1 * static_cast<double>(step);
  f.speed_mps = 20.0 + 0.01 * static_cast<double>(step);
  f.s_m = static_cast<double>(step);
  f.cars = std::move(cars);
  return f;
}

TEST_F(ReplayTest, CarsComingGoingAndJumpingFarComeBackExactly) {
  // 2.1e7 m is 2.1e9 cm, near the end of i32: a jump from one end to the other is a 5-byte
  // difference. Yaw goes round through ±π, speeds reach both ends of u16.
  constexpr double kFar = 2.1e7;
  std::vector<ReplayFrame> frames;
  frames.push_back(frame_at(0, 1.0, 2.0, {car(1, 10, 20), car(2, -5, 7), car(3, 0, 0)}));
  frames.push_back(frame_at(1, 1.5, 2.5, {car(3, 0.4, 0), car(1, 10.4, 20)}));  // 2 leaves
  frames.push_back(frame_at(
      2, kFar, -kFar, {car(2, -4, 7), car(3, 0.8, 0), car(1, 10.8, 20), car(65535, kFar, -kFar)}));
  frames.push_back(frame_at(3, -kFar, kFar, {}));  // everyone leaves
  frames.push_back(frame_at(
      5, 0.0, 0.0, {car(65535, -kFar, kFar, 3.14159, 655.35), car(1, 11, 20, -3.14159, 0.0)}));
  frames.push_back(
      frame_at(6, 0.01, 0.0, {car(1, 11.01, 20, 3.14159, 0.0), car(65535, kFar, -kFar)}));
  const std::vector<core::Vec2> path = {{kFar, kFar}, {-kFar, -kFar}, {0.0, 0.0}, {0.01, -0.01}};

  ReplayEncoder enc;
  std::string records;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    enc.append_frame(frames[i], records);
    if (i == 2 || i == 4) enc.append_path(path, records);
  }
  // A repeated id is left out, an id beyond u16 clamped.
  enc.append_frame(frame_at(7, 0.0, 0.0, {car(1, 11, 20), car(1, 99, 99), car(70000, 1, 1)}),
                   records);
  ReplayEncoder::append_end("{}", records);
  const Replay r = parse_replay(handmade(header(), records), "far.otr");

  ASSERT_EQ(r.frames.size(), frames.size() + 1);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    SCOPED_TRACE("frame " + std::to_string(i));
    const ReplayFrame& want = frames[i];
    const ReplayFrame& got = r.frames[i];
    EXPECT_EQ(got.step, want.step);
    EXPECT_EQ(cm(got.position.x), cm(want.position.x));
    EXPECT_EQ(cm(got.position.y), cm(want.position.y));
    EXPECT_EQ(std::llround(got.yaw_rad * 1e4), yaw_units(want.yaw_rad));
    EXPECT_EQ(cm(got.speed_mps), cm(want.speed_mps));
    EXPECT_EQ(f32(got.s_m), f32(want.s_m));
    ASSERT_EQ(got.cars.size(), want.cars.size());
    for (std::size_t k = 0; k < got.cars.size(); ++k) {
      EXPECT_EQ(got.cars[k].id, want.cars[k].id);
      EXPECT_EQ(cm(got.cars[k].position.x), cm(want.cars[k].position.x));
      EXPECT_EQ(cm(got.cars[k].position.y), cm(want.cars[k].position.y));
      EXPECT_EQ(std::llround(got.cars[k].yaw_rad * 1e4), yaw_units(want.cars[k].yaw_rad));
      EXPECT_EQ(cm(got.cars[k].speed_mps), cm(want.cars[k].speed_mps));
    }
  }
  ASSERT_EQ(r.paths.size(), 2u);
  EXPECT_EQ(r.paths[0].step, 2);
  EXPECT_EQ(r.paths[1].step, 5);
  for (const ReplayPath& p : r.paths) {
    ASSERT_EQ(p.points.size(), path.size());
    for (std::size_t k = 0; k < path.size(); ++k) {
      EXPECT_EQ(cm(p.points[k].x), cm(path[k].x));
      EXPECT_EQ(cm(p.points[k].y), cm(path[k].y));
    }
  }
  const ReplayFrame& last = r.frames.back();
  ASSERT_EQ(last.cars.size(), 2u);
  EXPECT_EQ(last.cars[0].id, 1);
  EXPECT_EQ(cm(last.cars[0].position.x), 1100);
  EXPECT_EQ(last.cars[1].id, 65535);
  EXPECT_EQ(cm(last.cars[1].position.x), 100);  // 70000, clamped to 65535
}

TEST_F(ReplayTest, EveryCutOfAFrameOrPathIsNamedAndWhatCameBeforeKept) {
  ReplayEncoder enc;
  std::string first, frame, path;
  enc.append_frame(frame_at(0, 1.0, 2.0, {car(1, 10, 20), car(2, -5, 7)}), first);
  enc.append_frame(frame_at(1, 2.1e7, -3.0, {car(2, 2.1e7, 7), car(1, -2.1e7, 20), car(300, 1, 1)}),
                   frame);
  enc.append_path(std::vector<core::Vec2>{{1e7, 0.0}, {-1e7, 5.0}}, path);
  // A frame's last 6 bytes (TTC and headway, added within version 2) may be missing: a frame
  // cut there is one from an older writer.
  constexpr std::size_t kOptionalFrameTail = 6;
  for (const std::string* rec : {&frame, &path}) {
    const std::string payload = rec->substr(kRecordHead);
    const std::size_t required = payload.size() - (rec == &frame ? kOptionalFrameTail : 0);
    for (std::size_t cut = 0; cut < required; ++cut) {
      SCOPED_TRACE("cut at " + std::to_string(cut) + " of " + std::to_string(payload.size()));
      std::string records =
          first + record_of(static_cast<std::uint8_t>((*rec)[0]), payload.substr(0, cut));
      ReplayEncoder::append_end("{}", records);
      const ReplayCheck c = check_replay(handmade(header(), records), "cut.otr");
      EXPECT_THAT(c.error, HasSubstr("cut.otr: corrupt: record #2 ("));
      EXPECT_THAT(c.error, HasSubstr("after record #1 (step 0, t = 0.00 s)"));
      EXPECT_EQ(c.frames, 1u);
    }
    std::string records = first + frame + path;
    ReplayEncoder::append_end("{}", records);
    EXPECT_EQ(check_replay(handmade(header(), records), "whole.otr").error, "");
  }
}

// A frame payload by hand (docs/replay.md): step, the ego's differences, floats, cars.
class FramePayload {
 public:
  explicit FramePayload(std::uint32_t step) { u32(step); }
  FramePayload& delta(std::int64_t v) {
    return uvarint((static_cast<std::uint64_t>(v) << 1) ^ static_cast<std::uint64_t>(v >> 63));
  }
  FramePayload& uvarint(std::uint64_t v) {
    for (; v >= 0x80; v >>= 7) bytes_.push_back(static_cast<char>((v & 0x7f) | 0x80));
    bytes_.push_back(static_cast<char>(v));
    return *this;
  }
  FramePayload& floats_and_count(std::uint8_t cars) {
    bytes_.append(36, '\0');
    bytes_.push_back(static_cast<char>(cars));
    return *this;
  }
  FramePayload& raw(std::string_view b) {
    bytes_ += b;
    return *this;
  }
  [[nodiscard]] std::string record() const { return record_of(1, bytes_); }

 private:
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) bytes_.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  }
  std::string bytes_;
};

TEST_F(ReplayTest, BadDifferencesAndIdsAreNamed) {
  const auto error = [&](const std::string& records) {
    return check_replay(handmade(header(), records), "bad.otr").error;
  };
  const auto still = [](std::uint32_t step) {
    FramePayload p(step);
    p.delta(0).delta(0).delta(0).delta(0);
    return p;
  };
  // Well made by hand: read.
  EXPECT_EQ(
      error(still(0).floats_and_count(1).uvarint(4).delta(-5).delta(6).delta(0).delta(1).record() +
            record_of(4, "{}")),
      "");
  EXPECT_THAT(error(still(0).floats_and_count(2).uvarint(4).uvarint(4).record()),
              HasSubstr("record #1 (frame, at inflated byte 0): car id 4 appears twice"));
  EXPECT_THAT(error(still(0).floats_and_count(1).uvarint(65536).record()),
              HasSubstr("car id 65536 is above 65535"));
  EXPECT_THAT(
      error(still(0).floats_and_count(1).uvarint(4).delta(0).delta(0).delta(0).delta(-1).record()),
      HasSubstr("a car's speed comes to -1, outside [0, 65535]"));
  EXPECT_THAT(
      error(still(0).floats_and_count(1).uvarint(4).delta(0).delta(0).delta(32768).record()),
      HasSubstr("a car's yaw comes to 32768, outside [-32768, 32767]"));
  FramePayload far(0);
  far.delta(std::int64_t{INT32_MAX} + 1).delta(0).delta(0).delta(0);
  EXPECT_THAT(error(far.record()), HasSubstr("the ego's x comes to 2147483648"));
  FramePayload endless(0);
  endless.raw("\xff\xff\xff\xff\xff\x01");  // six bytes: longer than a varint may be
  EXPECT_THAT(error(endless.record()),
              HasSubstr("the ego's position and speed hold a varint longer than 5 bytes"));
  EXPECT_THAT(error(still(0).record()),
              HasSubstr("8 bytes where 45 are needed"));  // no floats, no car count
  // A path whose sum leaves i32: one point, x = 0 + 2^31 (the zigzag 2^32), y = 0.
  const std::string path =
      record_of(2, std::string("\x01\x00", 2) + "\x80\x80\x80\x80\x10" + std::string(1, '\0'));
  EXPECT_THAT(error(still(0).floats_and_count(0).record() + path),
              HasSubstr("record #2 (path, at inflated byte"));
  EXPECT_THAT(error(still(0).floats_and_count(0).record() + path),
              HasSubstr("a path point's x comes to 2147483648"));
}

}  // namespace
}  // namespace overtake::replay

namespace overtake::replay {
namespace {

// Checkpoint records (kind 5): read back whole, each belonging to the frame before it; one
// before any frame, of another step or damaged is named.
TEST_F(ReplayTest, CheckpointsAreReadBackAndBadOnesNamed) {
  World world(map_, line_, params_, TrafficProfile::faithful, 1);
  RunOptions opts;
  Stepper run(world, opts);
  run.step();
  Checkpoint c;
  c.info.step = world.steps();
  c.info.t_s = world.time_s();
  c.info.traffic = "faithful";
  c.run = run.save();
  const std::string encoded = encode_checkpoint(c);

  ReplayEncoder enc;
  std::string records;
  Frame f = first_frame(world);
  f.step = world.steps();
  enc.append_frame(f, records);
  ReplayEncoder::append_checkpoint(encoded, records);
  ReplayEncoder::append_end("{}", records);
  const auto file = dir_ / "ck.otr";
  write_bytes(file, handmade(header(), records));
  const Replay r = read_replay(file);
  ASSERT_EQ(r.checkpoints.size(), 1U);
  EXPECT_EQ(r.checkpoints[0].step, 1);
  EXPECT_EQ(r.checkpoints[0].bytes, encoded);
  EXPECT_EQ(decode_checkpoint(r.checkpoints[0].bytes, "x"), c);

  std::string first;
  ReplayEncoder::append_checkpoint(encoded, first);
  write_bytes(file, handmade(header(), first));
  EXPECT_THAT(error_of(file), HasSubstr("a checkpoint before the first frame"));

  std::string other;
  ReplayEncoder e2;
  Frame g = first_frame(world);
  g.step = 7;
  e2.append_frame(g, other);
  ReplayEncoder::append_checkpoint(encoded, other);
  write_bytes(file, handmade(header(), other));
  EXPECT_THAT(error_of(file), HasSubstr("a checkpoint of step 1 at frame 7"));

  std::string damaged;
  ReplayEncoder e3;
  e3.append_frame(f, damaged);
  ReplayEncoder::append_checkpoint(encoded.substr(0, encoded.size() / 2), damaged);
  write_bytes(file, handmade(header(), damaged));
  EXPECT_THAT(error_of(file), HasSubstr("(checkpoint, at inflated byte"));
  EXPECT_THAT(error_of(file), HasSubstr("the state ends early"));
}

}  // namespace
}  // namespace overtake::replay
