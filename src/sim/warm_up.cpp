#include "overtake/sim/warm_up.hpp"

#include <array>
#include <bit>
#include <cmath>

#include "overtake/core/state_archive.hpp"
#include "overtake/core/wire_number.hpp"

namespace overtake::sim {
namespace {

constexpr std::string_view kMagic = "OVTKWARM";
constexpr std::uint32_t kVersion = 1;
/// The most points of one path (a program sends 50; the reference planner about 150).
constexpr std::size_t kMaxPathPoints = 100000;
constexpr std::size_t kMaxCars = 256;
constexpr std::size_t kEgoDoubles = 6;
constexpr std::size_t kCarDoubles = 6;
constexpr std::uint64_t kFnvOffset = 14695981039346656037ULL;
constexpr std::uint64_t kFnvPrime = 1099511628211ULL;

/// Reads or writes a path: its length, then each coordinate XOR the point's before it (the
/// part a cycle's path shares with the cycle before's then repeats byte for byte).
void io_path(core::StateArchive& ar, std::vector<core::Vec2>& path, std::string_view what) {
  const std::size_t n = ar.io_length(path.size(), kMaxPathPoints, what);
  if (ar.loading()) path.assign(n, {});
  std::uint64_t px = 0;
  std::uint64_t py = 0;
  for (core::Vec2& p : path) {
    ar.io_delta(p.x, px, what, core::kMaxPathCoordinateM * 10.0);
    ar.io_delta(p.y, py, what, core::kMaxPathCoordinateM * 10.0);
    ar.require(std::isfinite(p.x) && std::isfinite(p.y), "a path point: not finite");
  }
}

struct Previous {
  std::array<std::uint64_t, kEgoDoubles> ego{};
  std::array<std::uint64_t, 2> end{};
  std::vector<std::array<std::uint64_t, kCarDoubles>> cars;
  std::uint64_t step = 0;
};

void io_cycle(core::StateArchive& ar, WarmUpCycle& c, Previous& prev) {
  // The step as a difference from the cycle before's (a few steps): small numbers compress.
  std::int64_t step = c.step;
  std::int64_t delta = step - static_cast<std::int64_t>(prev.step);
  ar.io_range(delta, 0, std::int64_t{1} << 40, "step after the cycle before");
  step = static_cast<std::int64_t>(prev.step) + delta;
  c.step = static_cast<long>(step);
  prev.step = static_cast<std::uint64_t>(step);

  core::EgoObservation& e = c.telemetry.ego;
  const std::array<double*, kEgoDoubles> ego = {&e.position.x, &e.position.y, &e.yaw_rad,
                                                &e.speed_mps,  &e.s_m,        &e.d_m};
  for (std::size_t k = 0; k < kEgoDoubles; ++k) {
    ar.io_delta(*ego[k], prev.ego[k], "ego value", core::StateArchive::kMaxMetres);
  }
  io_path(ar, c.telemetry.previous_path, "previous path");
  ar.io_delta(c.telemetry.end_path.s_m, prev.end[0], "end of path", core::StateArchive::kMaxMetres);
  ar.io_delta(c.telemetry.end_path.d_m, prev.end[1], "end of path", core::StateArchive::kMaxMetres);
  std::vector<core::CarObservation>& cars = c.telemetry.cars;
  const std::size_t m = ar.io_length(cars.size(), kMaxCars, "cars");
  if (ar.loading()) cars.assign(m, {});
  if (prev.cars.size() < m) prev.cars.resize(m, {});
  for (std::size_t k = 0; k < m; ++k) {
    core::CarObservation& o = cars[k];
    ar.io_range(o.id, 0, 65535, "car id");
    const std::array<double*, kCarDoubles> v = {&o.position.x,     &o.position.y, &o.velocity_mps.x,
                                                &o.velocity_mps.y, &o.s_m,        &o.d_m};
    for (std::size_t f = 0; f < kCarDoubles; ++f) {
      ar.io_delta(*v[f], prev.cars[k][f], "car value", core::StateArchive::kMaxMetres);
    }
  }
  io_path(ar, c.answer, "answer");
}

void archive_warm_up(core::StateArchive& ar, WarmUp& w) {
  ar.magic(kMagic, "a warm-up");
  std::uint32_t version = kVersion;
  ar.io(version, "version");
  ar.require(version == kVersion, "version: not one this build reads");
  ar.io_range(w.in_step_cycles, 1, 100000, "cycles in a row that make a planner in step");
  ar.io(w.from_run_start, "from the run's start");
  Previous prev;
  ar.io_vector(w.cycles, kMaxWarmUpCycles, "cycles",
               [&prev](core::StateArchive& a, WarmUpCycle& c) { io_cycle(a, c, prev); });
}

std::uint64_t mix(std::uint64_t h, double v) {
  auto bits = std::bit_cast<std::uint64_t>(v);
  for (int i = 0; i < 8; ++i) {
    h ^= bits & 0xffU;
    h *= kFnvPrime;
    bits >>= 8U;
  }
  return h;
}

core::Vec2 as_read(core::Vec2 p) {
  return {core::wire_round(p.x), core::wire_round(p.y)};
}

}  // namespace

std::string encode_warm_up(const WarmUp& warm_up) {
  core::StateArchive ar;
  WarmUp copy = warm_up;
  archive_warm_up(ar, copy);
  return ar.take();
}

WarmUp decode_warm_up(std::string_view bytes, std::string_view name) {
  core::StateArchive ar(bytes, std::string(name));
  WarmUp w;
  archive_warm_up(ar, w);
  ar.expect_end();
  return w;
}

bool same_answer(std::span<const core::Vec2> a, std::span<const core::Vec2> b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!(as_read(a[i]) == as_read(b[i]))) return false;
  }
  return true;
}

std::uint64_t answer_digest(std::span<const core::Vec2> answer) {
  std::uint64_t h = kFnvOffset;
  h = mix(h, static_cast<double>(answer.size()));
  for (const core::Vec2& p : answer) {
    const core::Vec2 r = as_read(p);
    h = mix(mix(h, r.x), r.y);
  }
  return h;
}

void play_warm_up(const WarmUp& warm_up,
                  const std::function<core::PlanResult(const core::Telemetry&)>& planner,
                  const std::atomic<bool>* stop, WarmUpResult& result) {
  result = WarmUpResult{};
  result.cycles = warm_up.cycles.size();
  result.in_step_cycles = warm_up.in_step_cycles;
  result.from_run_start = warm_up.from_run_start;
  result.digests.reserve(warm_up.cycles.size());
  std::size_t run = 0;  // answers matched in a row so far
  for (const WarmUpCycle& c : warm_up.cycles) {
    if (stop && stop->load(std::memory_order_relaxed)) break;
    const core::PlanResult plan = planner(c.telemetry);
    const auto k = static_cast<long>(result.played);
    ++result.played;
    result.digests.push_back(answer_digest(plan.path));
    if (same_answer(plan.path, c.answer)) {
      ++result.matched;
      ++run;
      if (run == static_cast<std::size_t>(warm_up.in_step_cycles))
        result.in_step_after = result.played;
    } else {
      run = 0;
      result.in_step_after = 0;
      if (result.first_difference < 0) {
        result.first_difference = k;
        result.first_difference_step = c.step;
      }
      result.last_difference = k;
    }
  }
  const std::size_t need =
      std::min(result.cycles, static_cast<std::size_t>(warm_up.in_step_cycles));
  result.in_step = result.played == result.cycles && run >= need;
  if (result.in_step && result.in_step_after == 0) result.in_step_after = result.played;
}

long first_disagreement(const WarmUpResult& a, const WarmUpResult& b) {
  const std::size_t n = std::min(a.digests.size(), b.digests.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (a.digests[i] != b.digests[i]) return static_cast<long>(i);
  }
  return -1;
}

}  // namespace overtake::sim
